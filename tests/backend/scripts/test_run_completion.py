"""A script run against the console (the light app on an in-memory vehicle running the onboard
agent), on a manual clock: a step on completion goes, and the run is over, when the step
before it (the last) completes, as the vehicle reports it on a two-way link (its guidance
reporting ``holding`` only at the path's end *and* its depth), by the estimate on a one-way
link, never while that pattern still flies (issue 20: "completed" at 120 s, the last step
flying on to 248 s); a repeating last step leaves the vehicle "running until retasked". The
trigger loop sleeps on the console's clock, so nothing here waits in real time."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.api.scripts import POLL_S
from planner import VehicleState
from station.link import Capability
from tests.agent_link import AgentLink
from tests.backend.conftest import AUTH, MakeLightClient, advance, console_of
from tests.backend.scripts.test_scripts import CIRCLE, HOVER, STRAIGHT, doc, step
from tests.manual_clock import ManualClock

#: The hover's duration (s): it completes this long after the vehicle takes it.
HOVER_S = float(HOVER["duration"])
#: A straight at the in-memory vehicle's 2 m (so is the hover), then a hover on completion;
#: the run's last step is the hover.
STRAIGHT_THEN_HOVER = doc(
    step("straight", {**STRAIGHT, "depth": 2}, "at", 0), step("hover", HOVER, "after_previous")
)
#: From the in-memory vehicle's 2 m: 3 m of line, 4 m down, so the last of the depth is flown
#: in place at the line's end (the planner's ramp outlasts the line).
DEEP: dict[str, float | str] = {"speed": 0.3, "depth": 6, "duration": 10, "heading": 90}


def run(client: TestClient, script: dict[str, Any]) -> dict[str, Any]:
    r = client.post("/api/scripts/run", json={"script": script, "mode": "auto"}, headers=AUTH)
    assert r.status_code == 200, r.text
    body: dict[str, Any] = r.json()
    return body


def state(client: TestClient) -> dict[str, Any]:
    body: dict[str, Any] = client.get("/api/scripts/run").json()
    return body


def until(client: TestClient, clock: ManualClock, probe: Any, within_s: float) -> float:
    """Move the console's clock until ``probe(run state)`` holds (read on the app's event
    loop, where the clock's timers fire); the clock seconds it took."""
    console = console_of(client)

    def holds() -> bool:
        runner = console.runner
        return runner is not None and bool(probe(runner.state()))

    return float(client.portal.call(clock.advance_until, holds, within_s))  # type: ignore[union-attr]


def vehicle_flies_on(client: TestClient, link: AgentLink, t_s: float) -> None:
    """The in-memory vehicle's guidance at vehicle time ``t_s`` (it holds still), and the
    status it then publishes, on the app's event loop."""

    def tick() -> None:
        s = link.state
        link.state = VehicleState(s.x_m, s.y_m, s.z_m, s.heading_deg, s.speed_mps, t_s)
        link.agent.guidance.update(s.x_m, s.y_m, s.z_m, t_s)
        link.report()

    client.portal.call(tick)  # type: ignore[union-attr]


def vehicle_at(client: TestClient, link: AgentLink, x_m: float, y_m: float, z_m: float) -> None:
    """The in-memory vehicle flies along its plan's waypoints (guidance following, at
    ``z_m``) to ``(x_m, y_m, z_m)``, a second of vehicle time per waypoint, and reports."""

    def fly() -> None:
        s, g = link.state, link.agent.guidance
        t = s.t_s
        path = g.plan.path if g.plan is not None else None
        for i in range(len(path) if path is not None and g.mode.value == "running" else 0):
            t += 1.0
            assert path is not None
            g.update(path.xs[i], path.ys[i], z_m, t)
        t += 1.0
        link.state = VehicleState(x_m, y_m, z_m, s.heading_deg, 0.0, t)
        g.update(x_m, y_m, z_m, t)
        link.report()

    client.portal.call(fly)  # type: ignore[union-attr]


def test_two_way_a_step_on_completion_waits_for_the_vehicle_at_the_end_and_its_depth(
    make_light_client: MakeLightClient,
) -> None:
    """The straight's line ends 4 m above its depth: the hover waits, past the estimate, for
    the vehicle to report the straight complete, and the vehicle does not while it flies
    the rest of the depth in place (before issue 20's fix its guidance said ``holding`` at
    the line's end); at the depth it does, and the hover goes."""
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    started = run(
        client, doc(step("straight", DEEP, "at", 0), step("hover", HOVER, "after_previous"))
    )
    assert started["completion_by"] == "vehicle"
    done_s = started["steps"][0]["completion_s"]
    until(client, clock, lambda s: s["steps"][0]["state"] == "acknowledged", 5.0)
    advance(client, clock, done_s + 30.0)  # well past the straight's estimated completion
    waiting = state(client)
    assert waiting["steps"][1]["state"] == "pending" and waiting["waiting_for"] == "completion"
    assert waiting["summary"].startswith(
        "running (auto): step 2 (hover) goes when the vehicle reports step 1 (straight) "
        "complete, expected at "
    )
    active = link.agent.active
    assert active is not None
    end = (active.path.xs[-1], active.path.ys[-1])
    vehicle_at(client, link, *end, 3.0)  # at the line's end, 3 m above the depth
    assert link.agent.guidance.at_end
    assert console_of(client).hub.status["mode"] == "running"  # type: ignore[index]
    advance(client, clock, 3 * POLL_S)
    assert state(client)["steps"][1]["state"] == "pending"
    assert len(link.frames) == 1
    vehicle_at(client, link, *end, 6.0)  # at its depth: complete
    assert console_of(client).hub.status["mode"] == "holding"  # type: ignore[index]
    until(client, clock, lambda s: s["steps"][1]["state"] == "acknowledged", 2 * POLL_S)
    after = state(client)
    assert after["steps"][0]["state_text"].endswith(", as the vehicle reported")
    assert after["steps"][1]["sent_s"] >= after["steps"][0]["completed_s"] > done_s
    assert len(link.frames) == 2


def test_two_way_the_run_completes_when_the_vehicle_reports_the_hover_complete(
    make_light_client: MakeLightClient,
) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    started = run(client, STRAIGHT_THEN_HOVER)
    assert started["completion_by"] == "vehicle"
    # the straight goes at once; the hover when the vehicle reports the straight complete
    until(client, clock, lambda s: s["steps"][0]["state"] == "acknowledged", 5.0)
    active = link.agent.active
    assert active is not None
    vehicle_at(client, link, active.path.xs[-1], active.path.ys[-1], active.path.zs[-1])
    until(client, clock, lambda s: s["steps"][1]["state"] == "acknowledged", 5.0)
    waiting = state(client)
    assert waiting["running"] and waiting["waiting_for"] == "completion"
    assert waiting["summary"].startswith(
        "running (auto): every step sent; waiting for the vehicle to report step 2 (hover) "
        "complete, expected at "
    )
    # long after the plan's time, the vehicle still reports the hover running: not over
    vehicle_flies_on(client, link, link.state.t_s + HOVER_S / 2)
    advance(client, clock, 3 * HOVER_S)
    assert state(client)["outcome"] == "running"
    assert console_of(client).hub.status["mode"] == "running"  # type: ignore[index]
    # the vehicle reports the hover complete (holding): the run is over, as it reported
    vehicle_flies_on(client, link, link.state.t_s + HOVER_S)
    assert console_of(client).hub.status["mode"] == "holding"  # type: ignore[index]
    until(client, clock, lambda s: not s["running"], 2 * POLL_S)
    done = state(client)
    assert done["outcome"] == "completed" and done["completion_by"] == "vehicle"
    assert done["completed_s"] >= done["steps"][1]["sent_s"] + 3 * HOVER_S
    assert done["summary"].endswith("the vehicle reported step 2 (hover) complete")
    assert done["steps"][1]["acknowledged_by_vehicle"] is True


def test_one_way_the_completion_is_estimated_from_the_send_and_said_so(
    make_light_client: MakeLightClient,
) -> None:
    clock, link = ManualClock(), AgentLink(Capability.NONE)
    client = make_light_client(link, clock=clock)
    started = run(client, doc(step("hover", HOVER, "at", 0)))
    assert started["completion_by"] == "estimate"
    until(client, clock, lambda s: s["steps"][0]["state"] == "acknowledged", 30.0)
    sent = state(client)
    assert sent["steps"][0]["acknowledged_by_vehicle"] is False
    assert sent["steps"][0]["state_text"].endswith("(this link gives no acknowledgement)")
    # from the surface (no telemetry: the origin) the hover's descent outlasts its 30 s: the
    # estimate of the vehicle flying it
    takes_s = sent["steps"][0]["completion_s"]
    assert takes_s > HOVER_S
    expected = sent["steps"][0]["sent_s"] + takes_s
    assert sent["due_s"] == pytest.approx(expected)
    assert sent["running"]
    took = until(client, clock, lambda s: not s["running"], 2 * takes_s)
    done = state(client)
    assert done["outcome"] == "completed" and done["completion_by"] == "estimate"
    assert done["completed_s"] == pytest.approx(expected)
    assert done["elapsed_s"] >= expected - 1e-6  # not before its time
    assert took > 0.0
    assert "(estimated)" in done["summary"] and "reports nothing" in done["summary"]


def test_a_repeating_last_step_is_running_until_retasked(
    make_light_client: MakeLightClient,
) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    run(client, doc(step("hover", HOVER, "at", 0), step("circle", CIRCLE, "after_previous")))
    until(client, clock, lambda s: s["steps"][0]["state"] == "acknowledged", 5.0)
    vehicle_flies_on(client, link, link.state.t_s + HOVER_S)  # the hover complete, reported
    until(client, clock, lambda s: not s["running"], 2 * HOVER_S)
    done = state(client)
    assert done["outcome"] == "until_retasked"
    assert done["summary"] == "every step sent: step 2 (circle) is running until retasked"
    assert [s["state"] for s in done["steps"]] == ["acknowledged", "acknowledged"]
    assert link.agent.active is not None and link.agent.active.pattern == "circle"


def test_the_trigger_loop_waits_on_the_consoles_clock(make_light_client: MakeLightClient) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    run(client, doc(step("hover", HOVER, "at", 0), step("straight", STRAIGHT, "at", 60)))
    until(client, clock, lambda s: s["waiting_for"] == "time", 10.0)
    assert len(link.frames) == 1
    advance(client, clock, 1059.0 - clock.now_s)  # the run started at 1000 s
    assert len(link.frames) == 1  # not before its time, on the console's clock
    took = until(client, clock, lambda s: s["steps"][1]["state"] != "pending", 2.0)
    assert took <= 1.0 + POLL_S
    assert len(link.frames) == 2


def test_export_refuses_on_completion_and_keeps_a_time(client: TestClient) -> None:
    r = client.post("/api/scripts/export", json=STRAIGHT_THEN_HOVER)
    assert r.status_code == 422, r.text
    (detail,) = r.json()["detail"]
    assert detail["loc"] == ["body", "steps", 1, "trigger", "kind"]
    assert detail["type"] == "onboard_completion_trigger"
    assert detail["msg"].startswith("step 2 waits for step 1 (straight) to complete")
    assert "from the run's start" in detail["msg"]
    assert (
        client.post(
            "/api/scripts/export", params={"format": "csv"}, json=STRAIGHT_THEN_HOVER
        ).status_code
        == 422
    )
    timed = doc(step("straight", STRAIGHT, "at", 0), step("hover", HOVER, "at", 40))
    frames = client.post("/api/scripts/export", json=timed).json()["frames"]
    assert [(f["t_s"], f["pattern"]) for f in frames] == [(0.0, "straight"), (40.0, "hover")]
