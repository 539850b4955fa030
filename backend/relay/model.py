"""The relay as the API and the page show it: ``link.relay`` of a console without a
transmitter (``/api/vehicle``, every ``link`` message)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from station.link import Capability


class RelayView(BaseModel):
    """The console that holds the transmitter, as this one last read it from the log."""

    via: str | None = Field(
        default=None,
        description="the console holding the transmitter (the one seen most recently); null: "
        "no console has said it holds one",
    )
    target: str | None = Field(default=None, description="its transmitter's target")
    seen_age_s: float | None = Field(
        default=None, description="since it last said so (s, on the database's clock)"
    )
    fresh: bool = Field(
        default=False,
        description="it said so within the last few seconds (it beats every second): it "
        "takes this console's commands",
    )
    connected: bool | None = Field(default=None, description="its link to the vehicle is up")
    capability: Capability | None = Field(
        default=None, description="what the vehicle reports back over its link"
    )
    level: Literal["green", "amber", "red"] | None = Field(
        default=None, description="its link's health level"
    )
    problems: list[str] = Field(default_factory=list, description="its link's problems")
    datum_lat_deg: float | None = Field(
        default=None,
        description="its datum's latitude (deg): the origin of the positions it writes into the "
        "track (null: it has none)",
    )
    datum_lon_deg: float | None = Field(default=None, description="its datum's longitude (deg)")
    vehicles: list[str] | None = Field(
        default=None,
        description='the vehicles it sends to (its fleet\'s names; ["nemesys"]: the single '
        "vehicle); a command to any other is refused there. Null: not said",
    )
    telemetry_via: str | None = Field(
        default=None,
        description="the console whose track points in the shared mission log this console's "
        "pose and status are read from (at most one a second; ``last_telemetry_age_s`` since "
        "that console heard the vehicle); null: none read yet. This console never hears the "
        "vehicle itself",
    )
