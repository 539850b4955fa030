"""Link health: what the station knows of its link to the vehicle, and what is wrong with it.

This is the vehicle link, not the browser's websocket to the console. :class:`FrameLedger`
counts the frames that left the station and what became of them (over the last
:data:`WINDOW` frames and since the dive began); :func:`assess` turns that, the link's
capability and the ages of the last acknowledgement and telemetry into a green / amber / red
level and a list of named problems. :class:`LinkHealth` is what ``/api/vehicle`` gives under
``link``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Final, Literal

from pydantic import BaseModel

from backend.link import Capability

TYPE_CHECKING = False
if TYPE_CHECKING:
    from backend.commands import CommandManager
    from backend.link import Link
    from backend.telemetry import TelemetryHub

#: Frames in the "recent" window.
WINDOW: Final = 20
#: Telemetry older than this is a problem (s); at RED_TELEMETRY_S it is red.
STALE_TELEMETRY_S: Final = 3.0
RED_TELEMETRY_S: Final = 10.0
#: Unknown telemetry numbers (null / NaN / missing) this recent are a problem (s).
UNKNOWN_VALUES_RECENT_S: Final = 10.0

Level = Literal["green", "amber", "red"]
Outcome = Literal["sent", "awaiting", "acknowledged", "rejected", "timed_out"]
_ANSWERS: Final = ("acknowledged", "rejected", "timed_out")


class FrameCounts(BaseModel):
    """Frames that left the station, and what became of them."""

    #: Every frame that left.
    frames: int = 0
    #: Frames no acknowledgement was expected for (one-way link, or replaced before one came).
    sent: int = 0
    acknowledged: int = 0
    rejected: int = 0
    timed_out: int = 0


class FrameTotals(BaseModel):
    recent: FrameCounts
    dive: FrameCounts


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
    #: Delivery probability the number of copies is chosen to reach.
    delivery_target: float
    #: Copies a command gets now (chosen from ``ber`` and the delivery target).
    copies: int
    #: Copies a Surface gets now; null: repeated until acknowledged (two-way link).
    surface_copies: int | None


@dataclass
class _Slot:
    command_id: int
    outcome: Outcome


class FrameLedger:
    """Frames out and their fate: the last :data:`WINDOW` and the dive's totals."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """A new dive."""
        self._recent: deque[_Slot] = deque(maxlen=WINDOW)
        self._dive = FrameCounts()
        self._awaiting: dict[int, int] = {}  # command id -> its frames awaiting an answer

    def frame_out(self, command_id: int, *, answer_expected: bool) -> None:
        self._dive.frames += 1
        if answer_expected:
            self._awaiting[command_id] = self._awaiting.get(command_id, 0) + 1
            self._recent.append(_Slot(command_id, "awaiting"))
        else:
            self._dive.sent += 1
            self._recent.append(_Slot(command_id, "sent"))

    def settle(self, command_id: int, outcome: Outcome) -> None:
        """The command's frames awaiting an answer got ``outcome`` (``sent``: none will
        come, e.g. it was replaced)."""
        count = self._awaiting.pop(command_id, 0)
        setattr(self._dive, outcome, getattr(self._dive, outcome) + count)
        for slot in self._recent:
            if slot.command_id == command_id and slot.outcome == "awaiting":
                slot.outcome = outcome

    def totals(self) -> FrameTotals:
        recent = FrameCounts(frames=len(self._recent))
        for slot in self._recent:
            if slot.outcome != "awaiting":
                setattr(recent, slot.outcome, getattr(recent, slot.outcome) + 1)
        return FrameTotals(recent=recent, dive=self._dive.model_copy())


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
) -> tuple[Level, list[str]]:
    """The link's level and its problems, worst first."""
    red: list[str] = []
    amber: list[str] = list(capability_problems)
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
    link: Link, cm: CommandManager, hub: TelemetryHub, target: str, ber: float
) -> LinkHealth:
    """What the station knows of its link to the vehicle (not the page's websocket): the
    link's own facts, the command ledger's and the telemetry's ages, and the assessment."""
    totals = cm.ledger.totals()
    telemetry_age_s = hub.age_s()
    ack_age_s = None if cm.last_ack_s is None else cm.clock.monotonic() - cm.last_ack_s
    level, problems = assess(
        connected=link.connected,
        connection_problem=link.connection_problem,
        capability=link.capability,
        capability_problems=link.capability_problems,
        telemetry_age_s=telemetry_age_s,
        recent=totals.recent,
        unknown_recent=hub.unknown_recent(UNKNOWN_VALUES_RECENT_S),
    )
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
        ber=ber,
        delivery_target=cm.delivery_target,
        copies=cm.copies_now(),
        surface_copies=cm.surface_copies_now(),
    )
