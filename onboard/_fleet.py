"""The onboard agent's receive for a vehicle with an address, one of a fleet on a shared ME
link (docs/protocol.md, "Addressing"): loaded only by such a vehicle, so a vehicle with no
address holds none of it (``nemesys bench onboard`` measures its memory).

A 100-bit or a 108-bit frame goes through the addressed receiver
(:class:`codec.AddressedReceiver`): frames to this vehicle or to all, and the single-vehicle
Surface, are then run as any other (:meth:`onboard.agent.OnboardAgent._execute`); one for
another vehicle is acknowledged rejected ``other_vehicle``, with the ``address`` it named.
"""

from __future__ import annotations

from codec import (
    ADDRESSED_FRAME_BITS,
    ADDRESSED_FRAME_BYTES,
    FRAME_BITS,
    FRAME_BYTES,
    Accepted,
    AddressedFrame,
    AddressedReceiver,
    Frame,
    RejectReason,
)

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from onboard.agent import NoNavigation, OnboardAgent
    from onboard.guidance import Reference
    from planner import VehicleState


def receive_addressed(
    agent: OnboardAgent,
    address: int,
    bits: int | None,
    n_bits: int,
    state: VehicleState,
    t0: float,
    navigation: NoNavigation | None,
) -> tuple[dict[str, Any], Reference | None]:
    """:meth:`onboard.agent.OnboardAgent.receive` as vehicle ``address`` (1-15)."""
    if bits is None or n_bits not in (FRAME_BITS, ADDRESSED_FRAME_BITS):
        return agent._reject(
            state,
            None,
            None,
            RejectReason.MALFORMED.value,
            f"a frame is {FRAME_BITS} bits ({FRAME_BYTES} bytes), or {ADDRESSED_FRAME_BITS} "
            f"({ADDRESSED_FRAME_BYTES} bytes) addressed; got {n_bits} bits",
        ), None
    frame = Frame(bits) if n_bits == FRAME_BITS else AddressedFrame(bits)
    frame_hex = frame.hex
    events = AddressedReceiver(address).feed_bytes(frame.to_bytes())
    event = next((e for e in events if isinstance(e, Accepted)), events[-1] if events else None)
    if event is None:
        return agent._reject(
            state,
            frame_hex,
            None,
            RejectReason.NO_SYNC.value,
            "no preamble and delimiter found within the sync tolerance",
        ), None
    if not isinstance(event, Accepted):
        err = event.error
        ack = agent._reject(state, frame_hex, None, err.reason.value, str(err), err.field)
        ack["address"] = getattr(err, "address", None)  # whom it was for
        return ack, None
    return agent._execute(state, frame_hex, event.decoded, t0, navigation)
