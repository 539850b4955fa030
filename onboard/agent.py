"""The onboard agent: the code path a real NemeSys runs for every received frame.

received bits -> frame sync -> decode (BCH, CRC-4, dictionary checks) -> validation (a
flyable plan within the vehicle's limits) -> replan with the planner's retask join ->
guidance switch, then one acknowledgement per frame. A frame that fails any step is
acknowledged as rejected with the reason and changes nothing. The surface command (pattern
15) overrides everything: it is executed whatever the limits, mode or battery, and nothing
but a new command after it moves the vehicle again.

A frame carrying the command the vehicle already runs is acknowledged (``duplicate``) and
not replanned, so the console may repeat a command (Surface repeats until acknowledged)
without resetting the pattern.

Navigation: a vehicle that cannot plan now (no navigation yet, or stale: the caller says so
with :class:`NoNavigation`) still decodes and acknowledges every frame: a command that needs a
plan is rejected with ``no_navigation``; Surface is planned from the last known state, when
there is one. After a navigation fault the caller suspends the active command
(:meth:`OnboardAgent.suspend`): it is no longer flown, so the same command sent again is
replanned, not a duplicate. The agent keeps its recent acknowledgements
(:meth:`OnboardAgent.recent_acks`) for the status: a console that reconnects takes those it
missed from there.

Latencies are wall-clock (``time.perf_counter``) on this machine, as the paper measured them:
decode = receipt -> decoded and checked; replan = decoded -> plan built and the first new
setpoint out of guidance. No I/O here: the simulation (or a real vehicle's node) feeds it.
"""

from __future__ import annotations

import time

from codec import (
    FRAME_BITS,
    FRAME_BYTES,
    Accepted,
    Command,
    Decoded,
    Frame,
    RejectReason,
    receive_frame,
)
from onboard.guidance import Guidance, Reference
from planner import Limits, Plan, PlanError, VehicleState, plan, validate
from vehicle_contract.codes import (
    INVALID_PLAN,
    LIMIT_VIOLATION,
    NO_NAVIGATION,
    RECENT_ACKS_MAX,
    RECENT_ACKS_S,
)

TYPE_CHECKING = False
if TYPE_CHECKING:  # the onboard process imports no typing (~0.45 MiB): bench reconfig
    from typing import Any

#: The reject reasons beyond the codec's are the contract's (:mod:`vehicle_contract.codes`).
#: The pattern executed whatever the limits (pattern 15).
SURFACE = "surface"


def command_json(command: Command) -> dict[str, Any]:
    """A decoded command as JSON: pattern name and ID, parameters by name."""
    return {
        "pattern": command.pattern.name,
        "pattern_id": command.pattern.id,
        "params": dict(command.params),
    }


class NoNavigation:
    """Why the vehicle cannot plan now (:meth:`OnboardAgent.receive`'s ``navigation``).

    ``detail``: the reason in words, for the acknowledgement. ``last_known``: the state handed
    in is the last one the navigation gave (stale), so Surface is planned from it; False: the
    vehicle never had navigation (the state carries the time only) and nothing is planned.
    """

    __slots__ = ("detail", "last_known")

    def __init__(self, detail: str, last_known: bool) -> None:
        self.detail = detail
        self.last_known = last_known


class OnboardAgent:
    """Decodes, validates and switches guidance. One instance per vehicle.

    ``address``: ``None`` (no fleet) takes today's 100-bit frames, exactly as before; 1-15
    makes this vehicle one of a fleet on a shared link (docs/protocol.md, "Addressing"): it
    takes 108-bit addressed frames to it or to all, and of unaddressed frames only surface;
    one addressed to another vehicle is acknowledged rejected ``other_vehicle``, and every
    acknowledgement then says the ``address`` its frame carried.

    Raises:
        ValueError: an address that is no vehicle's (1-15), naming the range.
    """

    def __init__(
        self, guidance: Guidance, limits: Limits | None = None, address: int | None = None
    ) -> None:
        self.address = address
        if address is not None:  # a fleet's vehicle: its receive, loaded only then
            from codec import check_vehicle_address
            from onboard._fleet import receive_addressed

            check_vehicle_address(address)
            self._receive_addressed = receive_addressed
        self.guidance = guidance
        self.limits = limits or Limits()
        self.active: Plan | None = None
        #: The active command is no longer flown (a navigation fault): not a duplicate.
        self.suspended = False
        self.seq = 0
        self.accepted = 0
        self.rejected = 0
        self._recent: list[dict[str, Any]] = []  # the newest RECENT_ACKS_MAX, oldest first

    def suspend(self) -> None:
        """The active command stops being flown (the caller flies a fault action): the same
        command, sent again, is replanned from where the vehicle is then."""
        self.suspended = self.active is not None

    def recent_acks(self, t_s: float) -> list[dict[str, Any]]:
        """The acknowledgements made in the last ``RECENT_ACKS_S`` before ``t_s`` (at most
        ``RECENT_ACKS_MAX``), oldest first: the very objects returned by :meth:`receive`."""
        return [a for a in self._recent if t_s - a["t_s"] <= RECENT_ACKS_S]

    def receive(
        self,
        bits: int | None,
        n_bits: int,
        state: VehicleState,
        receipt_s: float | None = None,
        navigation: NoNavigation | None = None,
    ) -> tuple[dict[str, Any], Reference | None]:
        """Process one received frame: ``n_bits`` bits, first bit most significant.

        ``bits`` is ``None`` for a message that is not a frame at all (wrong length).
        ``receipt_s`` is the ``perf_counter`` time the bits arrived (default: now).
        ``navigation``: None when the vehicle's navigation is valid, else why not (a decoded
        command needing a plan is then rejected with ``no_navigation``). Returns the
        acknowledgement and, when accepted, guidance's first new reference.
        """
        t0 = time.perf_counter() if receipt_s is None else receipt_s
        self.seq += 1
        address = self.address
        if address is not None:
            return self._receive_addressed(self, address, bits, n_bits, state, t0, navigation)
        if bits is None or n_bits != FRAME_BITS:
            return self._reject(
                state,
                None,
                None,
                RejectReason.MALFORMED.value,
                f"a frame is {FRAME_BITS} bits ({FRAME_BYTES} bytes); got {n_bits} bits",
            ), None
        frame = Frame(bits)
        frame_hex = frame.hex
        events = receive_frame(frame.to_bytes())
        event = events[0] if events else None  # one accepted event: the common case
        if type(event) is not Accepted:  # else the first accepted one, or the last rejection
            event = next((e for e in events if isinstance(e, Accepted)), event and events[-1])
        if event is None:
            return self._reject(
                state,
                frame_hex,
                None,
                RejectReason.NO_SYNC.value,
                "no preamble and delimiter found within the sync tolerance",
            ), None
        if not isinstance(event, Accepted):
            err = event.error
            return self._reject(state, frame_hex, None, err.reason.value, str(err), err.field), None
        return self._execute(state, frame_hex, event.decoded, t0, navigation)

    def _execute(
        self,
        state: VehicleState,
        frame_hex: str,
        decoded: Decoded,
        t0: float,
        navigation: NoNavigation | None,
    ) -> tuple[dict[str, Any], Reference | None]:
        """A decoded frame: validated, planned and switched to, or rejected; acknowledged."""
        t1 = time.perf_counter()
        decode_ms = (t1 - t0) * 1e3
        command = decoded.command
        if navigation is not None and (
            command.pattern.name != SURFACE or not navigation.last_known
        ):
            return self._reject(
                state, frame_hex, decoded, NO_NAVIGATION, navigation.detail, None, decode_ms
            ), None
        current = self.active
        if current is not None and current.command == command and not self.suspended:
            return self._ack(state, frame_hex, decoded, decode_ms), None
        try:
            new = plan(command, state, current)
        except PlanError as err:
            return self._reject(
                state, frame_hex, decoded, INVALID_PLAN, str(err), err.field, decode_ms
            ), None
        if command.pattern.name != SURFACE:
            violations = validate(new, self.limits)
            if violations:
                first = violations[0]
                detail = "; ".join(v.message for v in violations)
                return self._reject(
                    state, frame_hex, decoded, LIMIT_VIOLATION, detail, first.param, decode_ms
                ), None
        self.active = new
        self.suspended = False
        self.guidance.set_plan(new, state.t_s)
        ref = self.guidance.update(state.x_m, state.y_m, state.z_m, state.t_s)
        replan_ms = (time.perf_counter() - t1) * 1e3
        return self._ack(state, frame_hex, decoded, decode_ms, new, replan_ms), ref

    # --- acknowledgements ----------------------------------------------------------------

    def _ack(
        self,
        state: VehicleState,
        frame_hex: str,
        decoded: Decoded,
        decode_ms: float,
        new: Plan | None = None,
        replan_ms: float | None = None,
    ) -> dict[str, Any]:
        """An accepted frame: ``new`` is the plan switched to, ``None`` for a duplicate of the
        active command."""
        self.accepted += 1
        pattern = decoded.command.pattern.name
        detail = (
            f"{pattern}: already active, not replanned"
            if new is None
            else f"{pattern}: replanned, {len(new.path)} waypoints"
        )
        return self._record(
            state, frame_hex, decoded, None, detail, None, decode_ms, new, replan_ms
        )

    def _reject(
        self,
        state: VehicleState,
        frame_hex: str | None,
        decoded: Decoded | None,
        reason: str,
        detail: str,
        field: str | None = None,
        decode_ms: float | None = None,
    ) -> dict[str, Any]:
        self.rejected += 1
        return self._record(state, frame_hex, decoded, reason, detail, field, decode_ms)

    def _record(
        self,
        state: VehicleState,
        frame_hex: str | None,
        decoded: Decoded | None,
        reason: str | None,
        detail: str,
        field: str | None,
        decode_ms: float | None,
        new: Plan | None = None,
        replan_ms: float | None = None,
    ) -> dict[str, Any]:
        """The acknowledgement of frame ``seq``: ``reason`` is ``None`` when it was accepted
        (kept among the recent ones)."""
        ack: dict[str, Any] = {
            "seq": self.seq,
            "t_s": state.t_s,
            "outcome": "accepted" if reason is None else "rejected",
            "frame_hex": frame_hex,
            "corrected_bits": decoded.corrected if decoded is not None else None,
            "sync_errors": decoded.sync_errors if decoded is not None else None,
            "reason": reason,
            "detail": detail,
            "field": field,
            "command": command_json(decoded.command) if decoded is not None else None,
            "duplicate": reason is None and new is None,
            "decode_latency_ms": decode_ms,
            "replan_latency_ms": replan_ms,
            "waypoints": len(new.path) if new is not None else None,
            "active": command_json(self.active.command) if self.active is not None else None,
            # the state the plan was made from: a console replays plan() from it and gets the
            # very path the vehicle flies (same anchor, same join)
            "from": state.as_dict() if new is not None else None,
        }
        if self.address is not None:  # a fleet's vehicle: the address its frame carried
            ack["address"] = getattr(decoded, "address", None)
        self._recent.append(ack)
        del self._recent[:-RECENT_ACKS_MAX]
        return ack
