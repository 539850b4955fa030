"""Link health: what the station knows of its link to the vehicle, and what is wrong with it.

This is the vehicle link, not the browser's websocket to the console. :class:`FrameLedger`
(:mod:`backend.commands.ledger`, its names still importable from here) counts the frames that
left the station and what became of them (over the last :data:`WINDOW` frames and since the
dive began); :func:`assess` turns that, the link's capability and the ages of the last
acknowledgement and telemetry into a green / amber / red level and a list of named problems.
:class:`LinkHealth` is what ``/api/vehicle`` gives under ``link``.
"""

from __future__ import annotations

from typing import Final, Literal

from pydantic import BaseModel, Field

from backend.commands.ledger import WINDOW, FrameCounts, FrameLedger, FrameTotals, Outcome
from backend.commands.link_ber import (
    BerNow,
    BerSource,
    ChannelEstimateView,
    CopiesFrom,
    estimate_view,
)
from backend.relay.model import RelayView
from station.link import Capability

TYPE_CHECKING = False
if TYPE_CHECKING:
    from backend.commands.manager import CommandManager
    from backend.telemetry import TelemetryHub
    from station.link import Link

__all__ = [
    "RED_TELEMETRY_S",
    "STALE_TELEMETRY_S",
    "UNKNOWN_VALUES_RECENT_S",
    "WINDOW",
    "FrameCounts",
    "FrameLedger",
    "FrameTotals",
    "Level",
    "LinkCheckView",
    "LinkHealth",
    "LinkTestResult",
    "MissionLogReach",
    "Outcome",
    "assess",
    "link_health_of",
]

#: Telemetry older than this is a problem (s); at RED_TELEMETRY_S it is red.
STALE_TELEMETRY_S: Final = 3.0
RED_TELEMETRY_S: Final = 10.0
#: Unknown telemetry numbers (null / NaN / missing) this recent are a problem (s).
UNKNOWN_VALUES_RECENT_S: Final = 10.0

Level = Literal["green", "amber", "red"]


class MissionLogReach(BaseModel):
    """Whether the console reaches its mission log's database now (a PostgreSQL server it
    shares with other consoles: :mod:`backend.control.sync`; a SQLite file is always
    reached). Unreached, every send is refused (503) until it is back."""

    reachable: bool = True
    problem: str | None = Field(default=None, description="why not, in the driver's words")
    since: str | None = Field(default=None, description="unreachable since (ISO 8601, UTC)")

    @property
    def refusal(self) -> str:
        """What the header says while it is unreached."""
        return f"mission log unreachable — sends refused ({self.problem or 'no answer'})"


class LinkHealth(BaseModel):
    """The vehicle link as the station knows it (``/api/vehicle`` -> ``link``)."""

    target: str
    connected: bool
    capability: Capability
    acknowledges: bool
    telemetry: bool
    level: Level
    problems: list[str]
    last_ack_age_s: float | None
    last_telemetry_age_s: float | None
    frames: FrameTotals
    #: Telemetry numbers that came as null, NaN or missing, since the dive began.
    unknown_values: int
    #: Bit-error rate the number of copies is chosen from.
    ber: float
    #: Where ``ber`` comes from: the emulated channel (training), the assumed BER, or the upper
    #: end of the estimate's interval (``copies_from``; the assumed BER until there is one).
    ber_source: BerSource
    #: The operator's choice of what the copies follow on a real link (``PUT /api/link``).
    copies_from: CopiesFrom
    #: The bit-error rate estimated from the dive's acknowledgements.
    channel: ChannelEstimateView
    #: Delivery probability the number of copies is chosen to reach.
    delivery_target: float
    #: Copies a command gets now (chosen from ``ber`` and the delivery target).
    copies: int
    #: Copies a Surface gets now; null: repeated until acknowledged (two-way link).
    surface_copies: int | None
    #: Whether the mission log's database is reached (not: every send refused, a red problem).
    mission_log: MissionLogReach = MissionLogReach()
    #: A console without a transmitter (target relay): the console that holds it, and its
    #: link; its problems are among ``problems``, named by it (null: this console transmits).
    relay: RelayView | None = None


class LinkCheckView(BaseModel):
    """One path of the link tested without sending a frame (``POST /api/link/test``)."""

    #: "modem" (an ME modem: its port or gateway opened and checked), "rosbridge" (the
    #: vehicle's rosbridge connection), "telemetry" (the hybrid link's rosbridge).
    what: str
    target: str
    ok: bool
    #: Why not, in a short phrase ("connection refused", "gateway not reading", ...).
    reason: str | None
    detail: str


class LinkTestResult(BaseModel):
    """``POST /api/link/test``: every path of the link checked now, no frame sent, and the
    link's health after it."""

    ok: bool
    checks: list[LinkCheckView]
    link: LinkHealth


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def assess(
    *,
    connected: bool,
    connection_problem: str | None,
    capability: Capability,
    capability_problems: list[str],
    telemetry_age_s: float | None,
    recent: FrameCounts,
    unknown_recent: int,
    datum_problem: str | None = None,
) -> tuple[Level, list[str]]:
    """The link's level and its problems, worst first (``datum_problem``: the vehicle's datum
    differs from the console's, :mod:`backend.chart.vehicle_datum`)."""
    red: list[str] = []
    amber: list[str] = list(capability_problems)
    if datum_problem is not None:
        amber.append(datum_problem)
    if not connected:
        red.append(connection_problem or "not connected to the vehicle")
    if capability.telemetry and connected:
        if telemetry_age_s is None:
            amber.append("no telemetry yet")
        elif telemetry_age_s > STALE_TELEMETRY_S:
            problem = f"no telemetry for {telemetry_age_s:.0f} s"
            (red if telemetry_age_s > RED_TELEMETRY_S else amber).append(problem)
    answered = recent.acknowledged + recent.rejected + recent.timed_out
    if recent.timed_out:
        problem = f"{recent.timed_out} of the last {_plural(answered, 'answered frame')} timed out"
        (red if recent.timed_out >= 2 and 2 * recent.timed_out >= answered else amber).append(
            problem
        )
    if recent.rejected:
        amber.append(
            f"{recent.rejected} of the last {_plural(answered, 'answered frame')} "
            "rejected by the vehicle"
        )
    if unknown_recent:
        amber.append(
            f"{_plural(unknown_recent, 'telemetry number')} unknown (null, NaN or missing) "
            f"in the last {UNKNOWN_VALUES_RECENT_S:.0f} s"
        )
    level: Level = "red" if red else "amber" if amber else "green"
    return level, red + amber


def link_health_of(
    link: Link,
    cm: CommandManager,
    hub: TelemetryHub,
    target: str,
    ber: BerNow,
    copies_from: CopiesFrom,
    datum_problem: str | None = None,
    mission_log: MissionLogReach | None = None,
    relay: RelayView | None = None,
    vehicle: str | None = None,
) -> LinkHealth:
    """What the station knows of its link to the vehicle (not the page's websocket): the
    link's own facts, the command ledger's and the telemetry's ages, and the assessment; a
    mission log that is not reached (``mission_log``) is the first problem, red: nothing can
    be sent. A fleet's ``vehicle``: ``link`` and ``hub`` are its own, and so are the ledger's
    counts."""
    v = cm.addressee(vehicle)
    totals = v.ledger.totals()
    telemetry_age_s = hub.age_s()
    ack_age_s = None if v.last_ack_s is None else cm.clock.monotonic() - v.last_ack_s
    level, problems = assess(
        connected=link.connected,
        connection_problem=link.connection_problem,
        capability=link.capability,
        capability_problems=link.capability_problems,
        telemetry_age_s=telemetry_age_s,
        recent=totals.recent,
        unknown_recent=hub.unknown_recent(UNKNOWN_VALUES_RECENT_S),
        datum_problem=datum_problem,
    )
    if relay is not None:  # this console hears nothing itself: its telemetry is the log's
        source = f"no telemetry via {relay.telemetry_via or relay.via or 'the shared'}'s log"
        problems = [p.replace("no telemetry", source, 1) for p in problems]
    if relay is not None and relay.fresh and relay.problems:
        named = [f"{relay.via}: {p}" for p in relay.problems]
        worst: Level = "red" if "red" in (level, relay.level) else "amber"
        level, problems = worst, [*problems, *named]
    reach = mission_log or MissionLogReach()
    if not reach.reachable:
        level, problems = "red", [reach.refusal, *problems]
    return LinkHealth(
        target=target,
        connected=link.connected,
        capability=link.capability,
        acknowledges=link.acknowledges,
        telemetry=link.telemetry,
        level=level,
        problems=problems,
        last_ack_age_s=ack_age_s,
        last_telemetry_age_s=telemetry_age_s,
        frames=totals,
        unknown_values=hub.unknown_values,
        ber=ber.ber,
        ber_source=ber.source,
        copies_from=copies_from,
        channel=estimate_view(v.ledger.channel),
        delivery_target=cm.delivery_target,
        copies=cm.copies_now(vehicle),
        surface_copies=cm.surface_copies_now(vehicle),
        mission_log=MissionLogReach.model_validate(reach.model_dump()),  # every field said
        relay=None if relay is None else RelayView.model_validate(relay.model_dump()),
    )
