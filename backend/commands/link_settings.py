"""``PUT /api/link``, ``POST /api/link/test`` and the BER the console's copies follow now
(what they are: :mod:`backend.commands.link_ber`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from backend.commands.health import LinkCheckView, LinkTestResult
from backend.commands.link_ber import COPIES_FROM_WORDS, BerNow, CopiesFrom
from backend.messages import EventMessage
from backend.mission_log.records import log_event
from backend.mission_log.store import LogWriteError

if TYPE_CHECKING:
    from backend.commands.health import LinkHealth
    from backend.console import Console


def ber_now(console: Console, vehicle: str | None = None) -> BerNow:
    """The BER the console's copies (to a fleet's ``vehicle``) follow now (the estimate is
    the dive's, so far: that vehicle's acknowledgements')."""
    emulated = None
    if console.sim is not None:
        config = console.sim.channel.config
        emulated = float(config.ber), float(config.loss)
    cm = console.commands
    estimate = None if cm is None else cm.addressee(vehicle).ledger.channel.estimate()
    return console.ber_choice.now(emulated, estimate)


def change_link(
    console: Console,
    operator: str,
    link_ber: float | None,
    delivery_target: float | None,
    copies_from: CopiesFrom | None,
) -> LinkHealth:
    """Change what the station assumes of its link (None: unchanged); later commands' copies
    follow. A new ``copies_from`` is logged (naming ``operator``) before it applies.

    Raises:
        ValueError: in training, ``link_ber`` or ``copies_from = "estimate_upper"`` (the
            emulated channel's BER is used); nothing is changed.
        LogWriteError: the choice could not be logged; nothing is changed.
    """
    cm, choice = console.commands, console.ber_choice
    assert cm is not None and console.log is not None
    if console.sim is not None and (link_ber is not None or copies_from == "estimate_upper"):
        what = "link_ber" if link_ber is not None else 'copies_from "estimate_upper"'
        raise ValueError(
            f"{what}: in training the copies follow the emulated channel's BER (the estimate "
            "is shown beside it): set it with PUT /api/training/channel"
        )
    if copies_from is not None and copies_from != choice.copies_from:
        detail = f"{operator} chose the copies to follow {COPIES_FROM_WORDS[copies_from]}"
        data = {"operator": operator, "copies_from": copies_from, "was": choice.copies_from}
        try:
            assert console.dives is not None
            event = console.dives.event("copies_from", detail, data)
        except LogWriteError as err:
            err.outcome = "nothing was changed"
            raise
        choice.copies_from = copies_from
        console.hub.publish(EventMessage(event=log_event(event)))
    if link_ber is not None:
        choice.assumed_ber = link_ber
    if delivery_target is not None:
        cm.delivery_target = delivery_target
    return console.link_health()


async def test_link(console: Console) -> LinkTestResult:
    """Check every path of the link now, sending no frame (a modem's port or gateway is opened
    if it is not open, and checked: :meth:`station.link.Link.test`); the health follows."""
    assert console.link is not None
    checks = [
        LinkCheckView(what=c.what, target=c.target, ok=c.ok, reason=c.reason, detail=c.detail)
        for c in await console.link.test()
    ]
    return LinkTestResult(ok=all(c.ok for c in checks), checks=checks, link=console.link_health())
