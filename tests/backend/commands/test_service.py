"""The command service on an in-memory link: the policy (hard refused, soft needs the
override, the override recorded), retry as a new command, and wire order."""

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
