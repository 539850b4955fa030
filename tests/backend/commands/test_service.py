"""The command service on an in-memory link: the policy (hard refused, soft needs the
override, the override recorded), retry as a new command, wire order, and its watchers (told
of every command before its first copy leaves; one may refuse)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pytest

from backend.commands.checks import SendViolation
from backend.commands.service import (
    Assessment,
    CommandService,
    LimitRefused,
    NotRetryableCommand,
    OverrideNeeded,
    SendOutcome,
    SendRefused,
    SendRequest,
    UnknownCommand,
    decide,
)
from codec import encode_frame
from tests.backend.commands.test_manager import CIRCLE, HOVER, ONE_WAY, Rig, run

DEEP = SendViolation(
    "depth_rating",
    "depth",
    "hard",
    "depth 105 m is beyond the 100 m rating",
    105,
    100,
    "m",
    "0 to 100 m",
)
FAST = SendViolation(
    "top_speed",
    "speed",
    "soft",
    "speed 0.5 m/s exceeds the 0.19 m/s top speed",
    0.5,
    0.19,
    "m/s",
    "up to 0.19 m/s",
)


def assessor(found: Mapping[str, tuple[SendViolation, ...]]) -> Any:
    """Checks that find ``found[pattern]`` (nothing for the others)."""

    def assess(pattern: str, params: Mapping[str, Any]) -> Assessment:
        return Assessment(encode_frame(pattern, dict(params)), found.get(pattern, ()))

    return assess


def service_of(
    rig: Rig, found: Mapping[str, tuple[SendViolation, ...]] | None = None
) -> CommandService:
    return CommandService(rig.cm, assessor(found or {}), "op")


CIRCLE_PARAMS = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
HOVER_PARAMS = {"duration": 60, "depth": 2, "heading": 90}


def test_decide_refuses_hard_whatever_the_override_and_soft_without_it() -> None:
    enc = encode_frame("hover", HOVER_PARAMS)
    for override in (False, True):
        with pytest.raises(LimitRefused) as hard:
            decide(Assessment(enc, (DEEP, FAST)), override)
        assert hard.value.status == 422 and DEEP in hard.value.violations
    with pytest.raises(OverrideNeeded) as soft:
        decide(Assessment(enc, (FAST,)), override=False)
    assert soft.value.status == 409 and soft.value.violations == (FAST,)
    assert "0.19 m/s top speed" in str(soft.value)
    assert decide(Assessment(enc, (FAST,)), override=True) == (FAST,)
    assert decide(Assessment(enc), override=False) == ()


def test_a_refused_send_writes_and_transmits_nothing(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        service = service_of(rig, {"circle": (DEEP,), "hover": (FAST,)})
        with pytest.raises(LimitRefused):
            await service.send(SendRequest("circle", CIRCLE_PARAMS, "api", override=True))
        with pytest.raises(OverrideNeeded):
            await service.send(SendRequest("hover", HOVER_PARAMS, "script", kind="script"))
        assert rig.log.commands() == [] and rig.link.frames == []

    run(tmp_path, ONE_WAY, scenario)


def test_an_override_is_recorded_with_who_and_which(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        service = service_of(rig, {"hover": (FAST,)})
        out = await service.send(SendRequest("hover", HOVER_PARAMS, "ws", override=True))
        record = rig.record(out.record.id)
        assert record["origin"] == "ws"
        assert record["overrides"] == {
            "by": "op",
            "violations": [{"check": "top_speed", "param": "speed", "message": FAST.message}],
        }
        await rig.until_state(record["id"], "sent")

    run(tmp_path, ONE_WAY, scenario)


def test_surface_is_never_refused_by_the_checks(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        service = service_of(rig, {"surface": (DEEP,)})
        out = await service.send(SendRequest("surface", {}, "script", kind="script"))
        assert out.record.kind == "surface" and out.record.origin == "script"

    run(tmp_path, ONE_WAY, scenario)


@pytest.mark.parametrize("state", ["interrupted", "timed_out", "failed", "rejected", "superseded"])
def test_a_retry_is_a_new_command_naming_the_old(tmp_path: Path, state: str) -> None:
    async def scenario(rig: Rig) -> None:
        service = service_of(rig)
        rec = await rig.cm.submit(CIRCLE, copies=1)
        await rig.until_state(rec["id"], "sent")
        rig.log.update_command(rec["id"], state=state, reason="made so by the test")
        again = (await service.retry(rec["id"], copies=2)).record
        assert again.id != rec["id"] and again.retry_of == rec["id"]
        assert again.state == "queued" and again.copies == 2
        assert again.origin == "retry" and again.created_at >= rec["created_at"]
        await rig.until_state(again.id, "sent")
        assert rig.state(rec["id"]) == state  # the old record keeps its state
        assert rig.link.count(CIRCLE) == 3

    run(tmp_path, ONE_WAY, scenario)


@pytest.mark.parametrize("state", ["sent", "acknowledged", "queued", "transmitted"])
def test_retry_refuses_other_states_and_unknown_ids(tmp_path: Path, state: str) -> None:
    async def scenario(rig: Rig) -> None:
        service = service_of(rig)
        rec = await rig.cm.submit(CIRCLE, copies=1)
        await rig.until_state(rec["id"], "sent")
        rig.log.update_command(rec["id"], state=state)
        with pytest.raises(NotRetryableCommand, match="superseded") as err:
            await service.retry(rec["id"])
        assert err.value.status == 409
        with pytest.raises(UnknownCommand) as unknown:
            await service.retry(999)
        assert unknown.value.status == 404

    run(tmp_path, ONE_WAY, scenario)


def test_a_retry_is_checked_like_any_send(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(HOVER, copies=1)
        await rig.until_state(rec["id"], "sent")
        rig.log.update_command(rec["id"], state="interrupted")
        # the vehicle has since moved where a hover breaks a limit
        service = service_of(rig, {"hover": (FAST,)})
        with pytest.raises(OverrideNeeded):
            await service.retry(rec["id"])
        assert len(rig.log.commands()) == 1 and rig.link.count(HOVER) == 1
        out = await service.retry(rec["id"], override=True)
        assert out.record.overrides is not None
        assert out.record.overrides.violations[0].check == "top_speed"

    run(tmp_path, ONE_WAY, scenario)


def test_wire_order_circle_surface_retry(tmp_path: Path) -> None:
    """A circle, a Surface that supersedes it, the circle retried: "last sent" is the circle
    and the log (oldest first) ends with it, in the order the first copies left."""

    async def scenario(rig: Rig) -> None:
        service = service_of(rig)
        circle = (await service.send(SendRequest("circle", CIRCLE_PARAMS, "api", copies=20))).record
        await rig.until(lambda: rig.link.count(CIRCLE) >= 1)
        surface = (await service.surface()).record
        await rig.until(lambda: rig.state(circle.id) == "superseded")
        await rig.until(lambda: rig.record(surface.id)["copies_sent"] >= 1)
        retried = (await service.retry(circle.id, copies=1)).record
        await rig.until_state(retried.id, "sent")
        assert rig.cm.last_sent is not None and rig.cm.last_sent["id"] == retried.id
        assert rig.cm.last_sent["pattern"] == "circle"
        oldest_first = [r["id"] for r in rig.log.commands(oldest_first=True)]
        assert oldest_first == [circle.id, surface.id, retried.id]
        assert rig.log.last_sent() == rig.cm.last_sent

    run(tmp_path, ONE_WAY, scenario)


class Recorder:
    """A watcher that notes what it hears and what the wire held when it heard it."""

    def __init__(self, rig: Rig, refuse: str | None = None) -> None:
        self.rig = rig
        self.refuse = refuse
        self.admitted: list[SendRequest] = []
        #: (origin, pattern, record id, its copies sent, frames on the wire) at ``sent``.
        self.heard: list[tuple[str, str, int, int, int]] = []

    def admit(self, request: SendRequest) -> None:
        self.admitted.append(request)
        if request.pattern == self.refuse:
            raise SendRefused(f"no {self.refuse} now")

    def sent(self, request: SendRequest, outcome: SendOutcome) -> None:
        rec = outcome.record
        wire = len(self.rig.link.frames)
        self.heard.append((request.origin, rec.pattern, rec.id, rec.copies_sent, wire))


def test_watchers_hear_of_every_path_before_its_first_copy_leaves(tmp_path: Path) -> None:
    """Send, Surface, retry, a scenario's and a script's sends: each is heard once, with its
    record written and no copy of it out yet (what lets a script run stop before it)."""

    async def scenario(rig: Rig) -> None:
        service = service_of(rig)
        seen = Recorder(rig)
        service.watch(seen)
        circle = (await service.send(SendRequest("circle", CIRCLE_PARAMS, "api", copies=1))).record
        await rig.until_state(circle.id, "sent")
        rig.log.update_command(circle.id, state="interrupted", reason="made so by the test")
        retried = (await service.retry(circle.id, copies=1)).record
        await rig.until_state(retried.id, "sent")
        hover = SendRequest("hover", HOVER_PARAMS, "scenario", copies=1)
        await rig.until_state((await service.send(hover)).record.id, "sent")
        step = SendRequest("hover", HOVER_PARAMS, "script", copies=1, kind="script")
        await rig.until_state((await service.send(step)).record.id, "sent")
        surface = (await service.surface()).record
        assert [(o, p) for o, p, *_ in seen.heard] == [
            ("api", "circle"),
            ("retry", "circle"),
            ("scenario", "hover"),
            ("script", "hover"),
            ("surface", "surface"),
        ]
        assert len(seen.admitted) == 5 and seen.heard[-1][2] == surface.id
        for n, (*_, copies_sent, wire) in enumerate(seen.heard):
            assert copies_sent == 0 and wire == n  # one frame out per earlier command, not its own

    run(tmp_path, ONE_WAY, scenario)


def test_a_watcher_refuses_before_anything_is_written(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        service = service_of(rig)
        seen = Recorder(rig, refuse="hover")
        service.watch(seen)
        with pytest.raises(SendRefused, match="no hover now"):
            await service.send(SendRequest("hover", HOVER_PARAMS, "script", kind="script"))
        assert rig.log.commands() == [] and rig.link.frames == [] and seen.heard == []

    run(tmp_path, ONE_WAY, scenario)
