"""The console's one settings class: environment variables ``NEMESYS_*`` or a settings file.

Defaults are the embedded training set-up: a simulated NemeSys behind its own rosbridge on
loopback, a local SQLite mission log, everything bound to 127.0.0.1. Point ``target`` at a
real vehicle's rosbridge (``ws://host:9090``) or an ME transmitter (``serial:///dev/ttyUSB0``,
``tcp://host:port``) instead, the latter with ``telemetry`` (``ws://host:9090``) when the
vehicle reports over a rosbridge (the hybrid link); ``relay`` is a console without a
transmitter of its own (the shore), its commands sent by the console that holds it through a
shared PostgreSQL log. A settings file
(``NEMESYS_SETTINGS=path``, ``KEY=value`` lines with the same ``NEMESYS_`` names) is read when
given.
"""

from __future__ import annotations

import os
import secrets
from pathlib import Path
from typing import Annotated, Any
from urllib.parse import urlsplit

from pydantic import BeforeValidator, Field, WithJsonSchema, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from codec import ASCII_DIGITS, number_from_text
from vehicle_contract.fleet import FleetVehicle

#: The target meaning "the embedded simulator" (training mode).
SIM_TARGET = "sim"
#: The target meaning "no transmitter here": commands go through the console that holds it
#: (the shared log's outbox, backend/relay/), which needs a PostgreSQL ``database_url``.
RELAY_TARGET = "relay"


def _number(value: object, *, text: bool) -> float | None:
    """A number; from text too when ``text`` (environment variables, settings files: ASCII
    decimal digits only, :func:`codec.number_from_text`); ``None`` for anything else
    (booleans are not numbers)."""
    if isinstance(value, str) and text:
        try:
            return number_from_text(value)
        except ValueError:
            return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def _got(value: object) -> str:
    """How a refused value is quoted, with the rule it broke when that was the digits."""
    hint = f" ({ASCII_DIGITS})" if isinstance(value, str) and not value.isascii() else ""
    return f"got {value!r:.40}{hint}"


def _checks(*, text: bool) -> tuple[BeforeValidator, BeforeValidator]:
    def link_ber(value: object) -> float:
        number = _number(value, text=text)
        if number is None or not 0.0 <= number < 0.5:
            raise ValueError(f"link_ber must be a number in [0, 0.5), {_got(value)}")
        return number

    def delivery_target(value: object) -> float:
        number = _number(value, text=text)
        if number is None or not 0.0 < number < 1.0:
            raise ValueError(f"delivery_target must be a number in (0, 1), {_got(value)}")
        return number

    return BeforeValidator(link_ber), BeforeValidator(delivery_target)


_TEXT_BER, _TEXT_TARGET = _checks(text=True)
_JSON_BER, _JSON_TARGET = _checks(text=False)
#: A link's bit-error rate, [0, 0.5), and a delivery probability to aim for, (0, 1): the
#: message names the field and the interval; never clamped. As settings (text accepted) and
#: as JSON request fields (numbers only).
LinkBer = Annotated[float, _TEXT_BER, Field(ge=0, lt=0.5)]
DeliveryTarget = Annotated[float, _TEXT_TARGET, Field(gt=0, lt=1)]
#: The request fields' bounds in JSON Schema keywords: after a validator, pydantic would
#: write ``Field(ge=...)`` under its own names, which the OpenAPI's readers ignore.
LinkBerIn = Annotated[
    float, _JSON_BER, WithJsonSchema({"type": "number", "minimum": 0, "exclusiveMaximum": 0.5})
]
DeliveryTargetIn = Annotated[
    float,
    _JSON_TARGET,
    WithJsonSchema({"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1}),
]


class Settings(BaseSettings):
    """Everything the console needs to start. Units in the names."""

    model_config = SettingsConfigDict(env_prefix="NEMESYS_", extra="forbid")

    host: str = "127.0.0.1"
    port: Annotated[int, Field(ge=0, le=65535)] = 8000
    viewer_host: str = "127.0.0.1"
    #: viser's own port (0: any free port; viser moves to the next free one if taken).
    viewer_port: Annotated[int, Field(ge=0, le=65535)] = 8080
    #: The live Foxglove view's port (docs/foxglove.md, "Live"): a read-only Foxglove
    #: WebSocket server on ``host`` (0: any free port). Unset: off.
    foxglove_port: Annotated[int, Field(ge=0, le=65535)] | None = None
    #: "sim" (training: the embedded simulator), ws://..., serial:///dev/..., tcp://host:port,
    #: or "relay" (no transmitter: the console holding it on the shared log sends).
    target: str = SIM_TARGET
    #: With an ME modem target: the vehicle's rosbridge (ws://host:port) that telemetry and
    #: acknowledgements come over, the frames going by the modem (the hybrid link). "": none.
    telemetry: str = ""
    #: The vehicle's ROS namespace: its topics are /<it>/nemesys/... (several vehicles in one
    #: graph; the reference node's vehicle_namespace parameter). "": /nemesys/...
    vehicle_namespace: str = ""
    #: A fleet on one ME link (docs/protocol.md, "Addressing"): a count (``3``: vehicles auv1,
    #: auv2, auv3 at addresses 1, 2, 3) or a JSON list of ``{"name", "address"}``
    #: (:func:`vehicle_contract.fleet.parse_vehicles`). "": the single vehicle, as always.
    #: On a console without a transmitter (target relay): the fleet of the console that holds
    #: it (the same names; a name it lacks is refused there, naming its vehicles).
    vehicles: str = ""
    #: Port of the embedded simulator's rosbridge (0: any free port), loopback only.
    sim_port: Annotated[int, Field(ge=0, le=65535)] = 0
    sim_seed: int = 0
    sim_time_scale: Annotated[float, Field(ge=0, le=50)] = 1.0
    db_path: Path = Path(".nemesys/missions.sqlite3")
    #: The mission log on a PostgreSQL server instead of the SQLite file ``db_path``:
    #: postgresql://user:password@host:5432/database (several consoles may share one).
    #: "": the SQLite file. (The token file stays beside ``db_path`` either way.)
    database_url: str = ""
    #: The operator token. Not set: the one kept beside the mission log, made on first use
    #: (backend/token_file.py: ``create_app`` and ``nemesys console`` put it here).
    token: Annotated[str, Field(min_length=16)] = Field(
        default_factory=lambda: secrets.token_urlsafe(24)
    )
    operator: Annotated[str, Field(min_length=1, max_length=40)] = "operator"
    #: This console's name among the consoles sharing a mission log (control, the records'
    #: ``console``, live sync: backend/control/). "": the one kept beside ``db_path``
    #: (``<db_path>.console``), made on first use from the host name.
    console_name: Annotated[
        str, Field(max_length=64, pattern=r"^([A-Za-z0-9][A-Za-z0-9._-]*)?$")
    ] = ""
    #: Control of a vehicle is released when the console holding it has not refreshed its
    #: heartbeat for this long, on the database's clock (s; PostgreSQL: several consoles).
    control_timeout_s: Annotated[float, Field(ge=1, le=3600)] = 15.0
    #: At start, take control of each vehicle no console controls (PostgreSQL; a SQLite log
    #: has one console, always in control).
    control_at_start: bool = True
    #: A relay console (target "relay") waits this long for the transmitting console's
    #: decision on a command (s); none by then: the command is withdrawn, nothing sent (504).
    relay_wait_s: Annotated[float, Field(ge=0.5, le=60)] = 5.0
    #: A console with a transmitter refuses a relayed command that waited longer than this
    #: in the outbox, on the database's clock (s): stale, never sent late.
    relay_max_age_s: Annotated[float, Field(ge=1, le=3600)] = 30.0
    bitrate_bps: Annotated[float, Field(gt=0, le=1e7)] = 36000.0
    #: Time allowed for an acknowledgement on top of airtime and the channel's delay (s).
    ack_timeout_s: Annotated[float, Field(gt=0, le=600)] = 5.0
    #: Surface is sent again this often (s): until acknowledged on a two-way link, a bounded
    #: number of times on a one-way link.
    surface_repeat_s: Annotated[float, Field(gt=0, le=60)] = 2.0
    #: Time between the copies of one command (s): longer than a burst of interference, so
    #: the copies' errors are independent.
    copy_interval_s: Annotated[float, Field(gt=0, le=60)] = 1.0
    #: Bit-error rate of a real link, for choosing how many copies a command gets (training
    #: takes it from the emulated channel).
    link_ber: LinkBer = 1e-3
    #: Probability that at least one copy of a command decodes, the number of copies is
    #: chosen to reach (a Surface aims for at least 0.999999).
    delivery_target: DeliveryTarget = 0.999
    #: Transmissions allowed per minute (Surface is never limited).
    max_sends_per_minute: Annotated[int, Field(ge=1, le=600)] = 30
    max_depth_m: Annotated[float, Field(gt=0, le=100)] = 100.0
    max_speed_mps: Annotated[float, Field(gt=0, le=2.55)] = 1.0
    telemetry_hz: Annotated[float, Field(gt=0, le=50)] = 10.0
    #: Largest request body accepted (bytes): a larger one is refused with 413 before it is
    #: read, parsed or authenticated. Also uvicorn's websocket message limit (above the /ws
    #: control cap, so an over-size control message gets an error reply).
    max_body_bytes: Annotated[int, Field(ge=8192, le=1 << 30)] = 65536
    #: Host names the console answers besides loopback names and the bound address (DNS
    #: rebinding: a request with any other Host is refused), e.g. ["console.ship"].
    allowed_hosts: list[Annotated[str, Field(min_length=1, max_length=253)]] = []
    #: Origins whose pages may open /ws besides the console's own (e.g. a chart plotter's).
    allowed_origins: list[Annotated[str, Field(min_length=1, max_length=300)]] = []

    # --- geo reference and chart (backend/chart/: geo.py, gps.py, tiles.py) -------------------
    #: Latitude and longitude of the NED origin (deg, WGS84). Unset: training uses its
    #: documented site (backend.chart.geo.TRAINING_DATUM); a real vehicle takes the surface GPS's
    #: first fix when ``gps`` is set, else has no datum (positions in metres only).
    datum_lat_deg: Annotated[float, Field(ge=-90, le=90)] | None = None
    datum_lon_deg: Annotated[float, Field(ge=-180, le=180)] | None = None
    #: The ME transmitter's (surface station's) position (deg); unset: the datum. A surface
    #: GPS, when set, moves it with each fix.
    station_lat_deg: Annotated[float, Field(ge=-90, le=90)] | None = None
    station_lon_deg: Annotated[float, Field(ge=-180, le=180)] | None = None
    #: Surface GPS, NMEA 0183: "" (none), udp://127.0.0.1:10110 or serial:///dev/ttyUSB1?baud=4800.
    gps: str = ""
    #: Reach of the ME link from the transmitter (m): the paper's 730 m.
    me_range_m: Annotated[float, Field(gt=0, le=100000)] = 730.0
    #: Optional local map tiles: a directory of z/x/y.png tiles or an .mbtiles file.
    tiles: Path | None = None

    # --- vehicle profile (backend/authoring/profile.py); unset: the twin's figures in training --
    #: Top speed through the water (m/s).
    top_speed_mps: Annotated[float, Field(gt=0, le=5)] | None = None
    #: Largest vertical speed (m/s): the descent's.
    heave_rate_mps: Annotated[float, Field(gt=0, le=5)] | None = None
    #: Largest ascent rate (m/s); unset: the heave rate's (or the twin's in training).
    ascent_rate_mps: Annotated[float, Field(gt=0, le=5)] | None = None
    #: Largest turn rate (deg/s).
    yaw_rate_dps: Annotated[float, Field(gt=0, le=360)] | None = None
    #: Time on a full battery at cruise (s).
    endurance_s: Annotated[float, Field(gt=0, le=1e7)] | None = None

    @field_validator("target")
    @classmethod
    def _target(cls, value: str) -> str:
        if value in (SIM_TARGET, RELAY_TARGET):
            return value
        from station.transmit import open_transmitter

        # parse only (raises ValueError naming the allowed forms); nothing is opened here
        open_transmitter(value).close()
        return value

    @field_validator("telemetry")
    @classmethod
    def _telemetry(cls, value: str) -> str:
        if not value.strip():
            return ""
        from station.link_modem import parse_telemetry

        return parse_telemetry(value)  # raises ValueError naming the allowed forms

    @model_validator(mode="after")
    def _relay_on_a_shared_log(self) -> Settings:
        if self.relay and not self.database_url:
            raise ValueError(
                "target 'relay' (a console without a transmitter, its commands sent by the "
                "console that holds it) needs the mission log the consoles share: set "
                "NEMESYS_DATABASE_URL=postgresql://user:password@host:port/database, the same "
                "as the transmitting console's"
            )
        return self

    @model_validator(mode="after")
    def _telemetry_with_a_modem(self) -> Settings:
        if self.telemetry and self.relay:
            raise ValueError(
                f"telemetry {self.telemetry!r} is for an ME modem target (serial:///dev/..., "
                "tcp://host:port, loop://); target 'relay' has no link of its own"
            )
        if self.telemetry and (self.training or self.target.startswith(("ws://", "wss://"))):
            raise ValueError(
                f"telemetry {self.telemetry!r} is for an ME modem target (serial:///dev/..., "
                f"tcp://host:port, loop://); target {self.target!r} "
                + (
                    "is the embedded simulator"
                    if self.training
                    else "is a rosbridge: it carries telemetry and acknowledgements itself"
                )
            )
        return self

    @field_validator("database_url")
    @classmethod
    def _database_url(cls, value: str) -> str:
        value = value.strip()
        scheme = urlsplit(value).scheme
        if value and scheme not in ("postgresql", "postgres"):
            # the scheme only: the rest may hold a password
            raise ValueError(
                "database_url must be postgresql://user:password@host:port/database, or empty "
                f"for the SQLite file db_path; got a URL of scheme {scheme or 'none'!r}"
            )
        return value

    @field_validator("vehicle_namespace")
    @classmethod
    def _vehicle_namespace(cls, value: str) -> str:
        from vehicle_contract.names import check_namespace

        return check_namespace(value)  # ValueError naming what a namespace may hold

    @field_validator("vehicles")
    @classmethod
    def _vehicles(cls, value: str) -> str:
        from vehicle_contract.fleet import parse_vehicles

        parse_vehicles(value)  # a FleetError (a ValueError) naming the fault and what is allowed
        return value.strip()

    @model_validator(mode="after")
    def _fleet_fits(self) -> Settings:
        if not self.fleet:
            return self
        if self.vehicle_namespace:
            raise ValueError(
                f"vehicle_namespace {self.vehicle_namespace!r} names one vehicle; with a fleet "
                "(vehicles) each vehicle's namespace is its name: leave vehicle_namespace empty"
            )
        return self

    @property
    def fleet(self) -> tuple[FleetVehicle, ...]:
        """The fleet the ``vehicles`` setting names (empty: the single vehicle)."""
        from vehicle_contract.fleet import parse_vehicles

        return parse_vehicles(self.vehicles)

    @field_validator("gps")
    @classmethod
    def _gps(cls, value: str) -> str:
        from backend.chart.gps import parse_gps

        parse_gps(value)  # raises ValueError naming the allowed forms; nothing is opened
        return value

    @property
    def mission_log(self) -> Path | str:
        """Where the mission log is: the PostgreSQL URL if set, else the SQLite file."""
        return self.database_url or self.db_path

    @property
    def mission_log_name(self) -> str:
        """The mission log as messages name it (a URL's password masked)."""
        from backend.mission_log.database import masked

        return masked(self.database_url) if self.database_url else str(self.db_path)

    @property
    def training(self) -> bool:
        return self.target == SIM_TARGET

    @property
    def relay(self) -> bool:
        """No transmitter here: the console holding it sends (``target`` "relay")."""
        return self.target == RELAY_TARGET

    @classmethod
    def load(cls, **overrides: Any) -> Settings:
        """Settings from the environment, the file named by NEMESYS_SETTINGS, and overrides."""
        path = os.environ.get("NEMESYS_SETTINGS")
        if path:
            return cls(_env_file=path, **overrides)  # type: ignore[call-arg]
        return cls(**overrides)
