"""When a script's step is complete (backend/scripts/completion.py), and that the timeline,
the onboard export and the run agree on it: a hover after its duration, a finite pattern at
the end of its path and its depth, as the vehicle is estimated to fly it (the one duration
story of issue 20: the kinematic twin, not the plan's own clock), a repeating pattern never
(the editor refuses to wait for one), and the stall of issue 14 (hover, then a circle on
completion) sends the circle."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.authoring.durations import flown
from backend.authoring.profile import twin_profile
from backend.scripts.completion import vehicle_verdict
from backend.scripts.labels import seconds
from backend.scripts.operations import (
    REPEATING,
    MissionScript,
    ScriptError,
    ScriptRunner,
    expand,
    export_onboard,
    flown_timing,
    preview,
)
from codec import PATTERNS, decode_frame, encode_frame
from planner import REPEATING_PATTERNS, Limits, VehicleState, plan
from sim.simulation import SimConfig, Simulation
from tests.backend.conftest import AUTH, TIME_SCALE, wait_until
from tests.backend.scripts.test_scripts import (
    CIRCLE,
    HOVER,
    LAWNMOWER,
    SQUARE,
    START,
    STRAIGHT,
    doc,
    errors_of,
    script,
    step,
)

REPO = Path(__file__).resolve().parents[3]
#: The issue's case: a hover, then a circle "when the previous pattern completes".
HOVER_THEN_CIRCLE = doc(step("hover", HOVER, "at", 0), step("circle", CIRCLE, "after_previous"))
#: How far the run's send times may be from the plan's, in vehicle seconds: the simulator's
#: clock moves in 20 ms ticks of wall time (1 s at 50x) and the run's loop wakes within a few
#: ms of a due time; 0.1 s of wall time (5 s at 50x) covers a loaded 2-core machine.
SEND_TOLERANCE_S = 0.1 * TIME_SCALE
#: The training vehicle's status reaches the console about every 0.4 s of wall time: 20 s of
#: vehicle time at 50x (a completion is heard up to that late).
STATUS_PERIOD_S = 0.4 * TIME_SCALE


# --- the rule ---------------------------------------------------------------------------


@pytest.mark.parametrize("pattern", [p.name for p in PATTERNS])
def test_each_pattern_is_finite_or_repeats_as_the_planner_plans_it(pattern: str) -> None:
    params = dict(next(p for p in PATTERNS if p.name == pattern).defaults)
    command = decode_frame(encode_frame(pattern, params).frame.bits).command
    p = plan(command, START)
    timing = flown_timing(None)(p)
    done = timing.completion_s
    if pattern in REPEATING:
        assert done is None
        assert p.path.loop_start is not None
        assert timing.duration_s == pytest.approx(flown(p, None)[0].duration_s)  # join + lap
    else:
        # complete where the path ends, at its depth, as the vehicle flies it: the estimate
        assert done is not None and done > 0.0
        assert done == pytest.approx(flown(p, None)[0].duration_s)
        assert p.path.loop_start is None
    assert REPEATING == REPEATING_PATTERNS == {"square", "circle"}


def test_the_page_knows_the_same_repeating_patterns() -> None:
    js = (REPO / "frontend" / "script_format.js").read_text()
    found = re.search(r"export const REPEATING = new Set\(\[([^\]]*)\]\)", js)
    assert found is not None, "frontend/script_format.js declares REPEATING"
    assert set(re.findall(r'"([a-z_]+)"', found.group(1))) == set(REPEATING)


def test_hover_completes_after_its_duration() -> None:
    s = MissionScript.model_validate(HOVER_THEN_CIRCLE)
    hov, circ = expand(s, START)
    assert hov.completion_s == pytest.approx(HOVER["duration"])
    assert circ.t_start_s == pytest.approx(30.0)  # not t = 0
    pv = preview(s, START)
    assert pv.steps[0].completion_s == pytest.approx(30.0)
    assert pv.steps[1].completion_s is None
    texts = {e.text: e.t_s for e in pv.timeline}
    retask = "circle retasks the vehicle (after step 1 completes, estimated)"
    assert texts[retask] == pytest.approx(30.0)
    done = [t for text, t in texts.items() if text.startswith("hover completes")]
    assert done == [pytest.approx(30.0)]
    # the onboard export refuses "on completion" rather than writing t = 30 s in its place
    with pytest.raises(ScriptError) as info:
        export_onboard(s, START)
    assert info.value.loc == ("steps", 1, "trigger", "kind")
    assert "step 1 is estimated to complete at 30 s from the run's start" in info.value.message


def test_hover_longer_than_its_approach_still_completes_at_its_duration() -> None:
    deep = {**HOVER, "depth": 4.0, "duration": 100}  # 2 m down at 0.05 m/s: 40 s of it
    s = script(step("hover", deep, "at", 10), step("straight", STRAIGHT, "after_previous"))
    hov, line = expand(s, START)
    assert hov.completion_s == pytest.approx(100.0)
    assert line.t_start_s == pytest.approx(110.0)


def test_finite_pattern_completes_at_its_path_end() -> None:
    s = script(
        step("lawnmower", LAWNMOWER, "at", 5),
        step("straight", STRAIGHT, "after_previous"),
        step("hover", HOVER, "after_previous"),
    )
    mow, line, hov = expand(s, START)
    assert mow.completion_s == pytest.approx(flown(mow.plan, None)[0].duration_s)
    assert line.t_start_s == pytest.approx(5.0 + (mow.completion_s or 0.0))
    assert line.completion_s == pytest.approx(flown(line.plan, None)[0].duration_s)
    assert hov.t_start_s == pytest.approx(line.t_start_s + (line.completion_s or 0.0))
    assert line.start_estimated and hov.start_estimated and not mow.start_estimated
    # the same times written as 'at' triggers (the operator's choice) export as they read
    timed = script(
        step("lawnmower", LAWNMOWER, "at", 5),
        step("straight", STRAIGHT, "at", round(line.t_start_s, 3)),
        step("hover", HOVER, "at", round(hov.t_start_s, 3)),
    )
    frames = export_onboard(timed, START)["frames"]
    assert [f["t_s"] for f in frames] == [
        pytest.approx(x.t_start_s, abs=1e-3) for x in (mow, line, hov)
    ]


def test_a_hover_retasking_a_hover_says_it_completes_sooner() -> None:
    # the vehicle is holding after a 30 s hover; the planner keeps a hover's clock on a retask
    first = decode_frame(encode_frame("hover", HOVER).frame.bits).command
    current = plan(first, VehicleState(0.0, 0.0, 2.0, t_s=100.0))
    s = MissionScript.model_validate(HOVER_THEN_CIRCLE)
    hov, circ = expand(s, START, current)
    assert hov.completion_s == pytest.approx(0.0)
    assert circ.t_start_s == pytest.approx(0.0)
    assert any("keeps that hover's clock" in w for w in hov.warnings)


# --- by the estimate, not the plan's own clock (issue 20) ------------------------------

#: The straight the operator reported: 0.18 m/s for 75 s, from the training vehicle's 2 m
#: down to 12.5 m. Its plan ramps the depth at 0.05 m/s (210 s); the vehicle descends at
#: its heave rate and is done at about 160 s.
REPORTED: dict[str, float | str] = {"speed": 0.18, "depth": 12.5, "duration": 75, "heading": 90}
#: The training vehicle at its start (idle at 2 m, heading north, at rest).
AT_TWO_M = VehicleState(0.0, 0.0, 2.0, heading_deg=0.0, speed_mps=0.0, t_s=0.0)


def reported_then_hover() -> MissionScript:
    return script(step("straight", REPORTED, "at", 0), step("hover", HOVER, "after_previous"))


def test_a_step_completes_when_the_vehicle_is_estimated_done_not_by_the_plans_clock() -> None:
    profile = twin_profile(Limits().max_depth_m)
    s = reported_then_hover()
    line, hov = expand(s, AT_TWO_M, None, flown_timing(profile))
    planned = line.plan.path.duration_s
    assert planned == pytest.approx(210.0, abs=5.0)  # the plan's own clock
    done = line.completion_s
    assert done == pytest.approx(flown(line.plan, profile)[0].duration_s)  # the estimate
    assert done is not None and done < planned - 30.0
    assert hov.t_start_s == pytest.approx(done)  # on completion: when it is estimated done
    # the simulator's own run of the same frame, timed by the same rule, agrees
    sim = Simulation(SimConfig(record_hz=0.0))
    sim.submit_frame(line.encoded.frame.to_bytes())
    while sim.completion.done_s is None and sim.t_s < 2 * planned:
        sim.advance(1.0)
    ran = sim.completion.done_s
    assert ran is not None and done == pytest.approx(ran, rel=0.10), (done, ran, planned)
    # the preview, the run and the export all say so, and that it is an estimate
    pv = preview(s, AT_TWO_M, None, None, flown_timing(profile))
    first = pv.steps[0]
    assert first.completion_s == pytest.approx(done) and first.planned_completion_s == planned
    assert first.timing_text == (
        f"starts at 0 s from the run's start, takes {seconds(done)} (estimated; "
        f"{seconds(planned)} by the plan's own clock)"
    )
    assert any("flown in place at the end" in n for n in first.duration_notes)
    assert pv.steps[1].start_estimated and pv.steps[1].t_start_s == pytest.approx(done)
    completes = [e for e in pv.timeline if e.text.startswith("straight completes")]
    assert [e.t_s for e in completes] == [pytest.approx(done)]
    assert completes[0].estimated and "(estimated: " in completes[0].text
    assert "estimated" in pv.durations_text
    runner = ScriptRunner.planned(s, expand(s, AT_TWO_M, None, flown_timing(profile)))
    assert runner.completion_s[0] == pytest.approx(done)
    with pytest.raises(ScriptError) as info:
        export_onboard(s, AT_TWO_M, None, flown_timing(profile))
    assert f"complete at {seconds(done)} from the run's start" in info.value.message


def test_the_next_step_starts_where_the_estimate_has_the_vehicle() -> None:
    """A step 'at' a time mid-way through a slower-than-planned step starts where the
    estimate has the vehicle then, not where the plan's clock would (further on)."""
    profile = twin_profile(Limits().max_depth_m)
    fast = {**STRAIGHT, "speed": 0.4, "duration": 60}  # above the twin's ~0.19 m/s
    s = script(step("straight", fast, "at", 0), step("hover", HOVER, "at", 30))
    line, hov = expand(s, START, None, flown_timing(profile))
    assert line.completion_s is not None and line.completion_s > line.plan.path.duration_s
    by_plan = line.plan.path.sample(30.0)
    travelled = math.hypot(hov.state.x_m - START.x_m, hov.state.y_m - START.y_m)
    assert travelled < 0.7 * math.hypot(by_plan.x_m - START.x_m, by_plan.y_m - START.y_m)
    assert not hov.start_estimated  # its time is set


# --- the editor refuses to wait for a repeating pattern ---------------------------------


@pytest.mark.parametrize(("pattern", "params"), [("circle", CIRCLE), ("square", SQUARE)])
def test_on_completion_after_a_repeating_step_is_refused(
    pattern: str, params: dict[str, float | str]
) -> None:
    data = doc(
        step("hover", HOVER, "at", 0),
        step(pattern, params, "after_previous"),
        step("straight", STRAIGHT, "after_previous"),
    )
    errors = errors_of(data)
    assert list(errors) == ["steps.2.trigger.kind"]
    assert errors["steps.2.trigger.kind"] == (
        f"step 3 waits for step 2 ({pattern}) to complete, but a {pattern} repeats until "
        "retasked, so it never completes: use a time ('at') or the operator's go"
    )
    # the alternatives the message names are accepted
    for kind, t_s in (("at", 300.0), ("operator", None)):
        data["steps"][2]["trigger"] = {"kind": kind, **({"t_s": t_s} if t_s else {})}
        MissionScript.model_validate(data)


def test_api_refuses_on_completion_after_a_circle_with_the_message(client: TestClient) -> None:
    bad = doc(step("circle", CIRCLE, "at", 0), step("hover", HOVER, "after_previous"))
    for method, url, body in (
        ("POST", "/api/scripts/preview", bad),
        ("POST", "/api/scripts/export", bad),
        ("POST", "/api/scripts/run", {"script": bad, "mode": "auto"}),
    ):
        r = client.request(method, url, json=body, headers=AUTH)
        assert r.status_code == 422, (url, r.text)
        detail = r.json()["detail"]
        assert len(detail) == 1
        prefix = ["body", "script"] if url.endswith("/run") else ["body"]
        assert detail[0]["loc"] == [*prefix, "steps", 1, "trigger", "kind"]
        assert detail[0]["msg"].startswith("step 2 waits for step 1 (circle) to complete")
        assert "repeats until retasked" in detail[0]["msg"]
    assert client.get("/api/commands").json() == []


# --- live: the run agrees with the timeline and the export ------------------------------


def first_pose(client: TestClient) -> None:
    wait_until(lambda: client.get("/api/vehicle").json()["pose"], what="a pose")


def run_to_the_end(
    client: TestClient, body: dict[str, Any], timeout_s: float, outcome: str = "completed"
) -> dict[str, Any]:
    r = client.post("/api/scripts/run", json={"script": body, "mode": "auto"}, headers=AUTH)
    assert r.status_code == 200, r.text
    done: dict[str, Any] = wait_until(
        lambda: (s := client.get("/api/scripts/run").json())["running"] is False and s,
        timeout_s=timeout_s,
        what="the run to finish",
    )
    assert done["outcome"] == outcome, done["reason"]
    return done


@pytest.mark.training
def test_the_issue_stall_now_sends_the_circle(client: TestClient) -> None:
    first_pose(client)
    # the vehicle has flown a hover and holds: the script's hover retasks it
    r = client.post("/api/commands", json={"pattern": "hover", "params": HOVER}, headers=AUTH)
    assert r.status_code == 202, r.text
    wait_until(
        lambda: (client.get("/api/vehicle").json()["status"] or {}).get("mode") == "holding",
        timeout_s=30,
        what="the first hover complete",
    )
    pv = client.post("/api/scripts/preview", json=HOVER_THEN_CIRCLE).json()
    assert any("keeps that hover's clock" in w for w in pv["warnings"])
    done = run_to_the_end(client, HOVER_THEN_CIRCLE, timeout_s=30, outcome="until_retasked")
    assert [s["state"] for s in done["steps"]] == ["acknowledged", "acknowledged"]
    assert done["summary"] == "every step sent: step 2 (circle) is running until retasked"
    wait_until(
        lambda: (client.get("/api/vehicle").json()["status"] or {}).get("pattern") == "circle",
        what="the vehicle flying the circle",
    )


@pytest.mark.training
def test_timeline_export_and_run_agree(client: TestClient) -> None:
    first_pose(client)
    body = doc(
        step("hover", {**HOVER, "duration": 60}, "at", 0),
        # 0.3 m/s, above the twin's 0.19 m/s top speed: the operator's override
        {**step("lawnmower", LAWNMOWER, "after_previous"), "override": True},
        step("circle", CIRCLE, "after_previous"),
    )
    pv = client.post("/api/scripts/preview", json=body).json()
    starts = [s["t_start_s"] for s in pv["steps"]]
    assert starts[1] == pytest.approx(60.0)  # the hover's duration, not t = 0
    assert starts[2] > starts[1] + 60.0  # the lawnmower's path
    timeline = {e["step"]: e["t_s"] for e in pv["timeline"] if "retasks" in e["text"]}
    assert [timeline[1], timeline[2]] == pytest.approx(starts[1:])
    # the onboard script cannot carry "on completion": refused, naming the step and the time
    r = client.post("/api/scripts/export", json=body)
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"] == ["body", "steps", 1, "trigger", "kind"]
    assert "at 60 s from the run's start" in r.json()["detail"][0]["msg"]
    done = run_to_the_end(
        client, body, timeout_s=20 + starts[2] / TIME_SCALE * 3, outcome="until_retasked"
    )
    steps = done["steps"]
    sent = [s["sent_s"] for s in steps]
    assert sent[0] == pytest.approx(0.0, abs=SEND_TOLERANCE_S)
    # the run's own plan (from where the vehicle was when it started) matches the preview's
    assert [s["completion_s"] for s in steps[:2]] == pytest.approx(
        [pv["steps"][0]["completion_s"], pv["steps"][1]["completion_s"]], abs=0.5
    )
    # each step on completion went out once the vehicle reported its predecessor complete,
    # as long after the send as the estimate said, give or take the twin's differences (20 %)
    # and a status period (the training status reaches the console every ~20 vehicle s)
    for i in (1, 2):
        before = steps[i - 1]
        reported = before["completed_s"]
        assert reported is not None, before
        assert sent[i] >= reported - 1e-6
        assert sent[i] <= reported + SEND_TOLERANCE_S
        took, estimated = reported - before["sent_s"], before["completion_s"]
        assert 0.8 * estimated <= took <= 1.2 * estimated + STATUS_PERIOD_S, (i, took, estimated)
        assert before["state_text"].endswith(", as the vehicle reported")


def test_a_navigation_fault_ends_the_step_like_an_empty_battery() -> None:
    """A vehicle whose navigation went stale flies its fault action (hold or surface) and says
    nav_fault until it accepts a command again: the step will not complete, in words."""
    params = {"depth": 4.0, "duration": 60.0}
    hover = {"pattern": "hover", "params": params}
    fault = {"t_s": 300.0, "mode": "nav_fault", "pattern": "hover", "active": hover}
    verdict, why = vehicle_verdict({**fault, "nav_age_s": 12.4}, "hover", params, 250.0)
    assert verdict == "ended"
    assert why == (
        "the vehicle's navigation went stale during the hover (nav_fault, its last navigation "
        "12 s old): it holds or surfaces from where it last knew it was, and cannot report the "
        "step complete until navigation is back and it accepts a command again"
    )
    assert vehicle_verdict(fault, "hover", params, 250.0)[1].startswith(
        "the vehicle's navigation went stale during the hover (nav_fault): "
    )
    running = {**fault, "mode": "running"}
    assert vehicle_verdict(running, "hover", params, 250.0)[0] == "running"
