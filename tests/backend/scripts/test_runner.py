"""The script run's state machine: triggers on the run clock, acknowledgements, the
operator's go, failures, and completion: as the vehicle reports it where its status reaches
the console (a step on completion waits for it, as the run's end does), else by the
estimate, said to be estimated."""

from __future__ import annotations

import json
from collections.abc import Callable

import pytest

from backend.authoring.profile import twin_profile
from backend.scripts.operations import (
    CompletionBy,
    MissionScript,
    RunMode,
    ScriptRunError,
    ScriptRunner,
    expand,
    flown_timing,
)
from codec import decode_frame, encode_frame
from planner import Limits
from tests.backend.scripts.test_scripts import (
    CIRCLE,
    HOVER,
    LAWNMOWER,
    START,
    STRAIGHT,
    script,
    step,
)

#: The estimated completions the tests give the runner (s after each step takes effect).
STRAIGHT_DONE_S = 40.0
MOW_DONE_S = 150.0
HOVER_DONE_S = 30.0


def three_step() -> MissionScript:
    return script(
        step("straight", STRAIGHT, "at", 0),
        step("lawnmower", LAWNMOWER, "at", 60),
        step("hover", HOVER, "after_previous"),
    )


def runner(mode: RunMode = "auto", start_s: float | None = None) -> ScriptRunner:
    return ScriptRunner(
        three_step(),
        mode,
        completion_s=[STRAIGHT_DONE_S, MOW_DONE_S, HOVER_DONE_S],
        start_s=start_s,
    )


def test_auto_sends_first_step_immediately_once() -> None:
    r = runner()
    assert r.state()["waiting_for"] == "time"
    assert r.poll(1000.0) == [0]
    assert r.poll(1000.0) == []
    assert r.poll(1001.0) == []
    st = r.state()
    assert st["waiting_for"] == "acknowledgement"
    assert st["steps"][0]["state"] == "sent"
    assert st["steps"][0]["sent_s"] == 0.0
    assert st["step"] == 1


def test_auto_at_step_waits_for_time_and_acknowledgement() -> None:
    r = runner()
    assert r.poll(1000.0) == [0]
    r.mark_sent(0)
    # at 60 s into the run, but step 0 not acknowledged yet: nothing
    assert r.poll(1070.0) == []
    assert r.state()["waiting_for"] == "acknowledgement"
    r.mark_acknowledged(0)
    assert r.state()["steps"][0]["state"] == "acknowledged"
    # late: due at once after the ack
    assert r.poll(1071.0) == [1]
    assert r.state()["steps"][1]["sent_s"] == 71.0


def test_auto_at_step_not_before_its_time() -> None:
    r = runner()
    assert r.poll(1000.0) == [0]
    r.mark_acknowledged(0)
    assert r.poll(1030.0) == []
    st = r.state()
    assert st["waiting_for"] == "time"
    assert st["due_s"] == 60.0  # from the run's start
    assert st["elapsed_s"] == 30.0
    assert r.poll(1059.9) == []
    assert r.poll(1060.0) == [1]
    assert r.poll(1061.0) == []


def test_explicit_start_time() -> None:
    r = runner(start_s=900.0)
    assert r.poll(950.0) == [0]
    r.mark_acknowledged(0)
    assert r.poll(960.0) == [1]


def test_after_previous_is_due_the_estimated_completion_after_the_previous_send() -> None:
    r = runner()
    assert r.poll(0.0) == [0]
    r.mark_acknowledged(0)
    assert r.poll(62.5) == [1]  # the lawnmower goes out at 62.5 s (a late poll)
    r.mark_sent(1)
    r.mark_acknowledged(1)
    st = r.state()
    assert st["waiting_for"] == "completion"
    assert st["due_s"] == 62.5 + MOW_DONE_S
    # a link that reports nothing: no vehicle report is waited for
    assert r.poll(62.5 + MOW_DONE_S - 0.1) == []
    assert r.poll(62.5 + MOW_DONE_S) == [2]
    assert r.poll(62.5 + MOW_DONE_S + 1) == []
    r.mark_acknowledged(2)
    # every step acknowledged, but the hover flies on: the run waits for it to complete
    st = r.state()
    assert st["running"] and st["outcome"] == "running"
    assert st["waiting_for"] == "completion" and st["step"] is None
    assert st["due_s"] == 62.5 + MOW_DONE_S + HOVER_DONE_S  # expected, by the estimate
    assert r.poll(62.5 + MOW_DONE_S + HOVER_DONE_S) == []  # completion_by "estimate"
    st = r.state()
    assert not st["running"]
    assert st["outcome"] == "completed"
    assert st["completed_s"] == 62.5 + MOW_DONE_S + HOVER_DONE_S
    assert st["waiting_for"] is None and st["due_s"] is None
    assert st["step"] is None
    assert [x["state"] for x in st["steps"]] == ["acknowledged"] * 3
    assert [x["completion_s"] for x in st["steps"]] == [STRAIGHT_DONE_S, MOW_DONE_S, 30.0]


def test_completion_waits_for_the_acknowledgement_too() -> None:
    s = script(step("hover", HOVER, "at", 0), step("circle", CIRCLE, "after_previous"))
    r = ScriptRunner(s, "auto", completion_s=[HOVER_DONE_S, None])
    assert r.poll(0.0) == [0]
    assert r.poll(HOVER_DONE_S + 5) == []  # due, but the hover is not acknowledged
    assert r.state()["waiting_for"] == "acknowledgement"
    r.mark_acknowledged(0)
    assert r.poll(HOVER_DONE_S + 6) == [1]


def test_a_hover_that_completes_at_once_does_not_stall_the_run() -> None:
    # issue 14: a hover retasking a hover in force completes at once; the circle must go
    s = script(step("hover", HOVER, "at", 0), step("circle", CIRCLE, "after_previous"))
    r = ScriptRunner(s, "auto", completion_s=[0.0, None])
    assert r.poll(10.0) == [0]
    r.mark_acknowledged(0)
    assert r.poll(10.2) == [1]


def test_default_completion_times_come_from_the_expansion() -> None:
    s = three_step()
    r = ScriptRunner(s, "auto")
    assert r.completion_s[1] == pytest.approx(expand(s, START)[1].duration_s, rel=0.05)
    assert r.completion_s[2] == pytest.approx(30.0)
    planned = ScriptRunner.planned(s, expand(s, START))
    assert planned.completion_s == tuple(x.completion_s for x in expand(s, START))


def test_a_clock_drives_poll_and_go() -> None:
    now = [5.0]
    s = script(step("straight", STRAIGHT, "at", 0), step("hover", HOVER, "operator"))
    r = ScriptRunner(s, "auto", completion_s=[STRAIGHT_DONE_S, 30.0], clock=lambda: now[0])
    assert r.poll() == [0]
    r.mark_acknowledged(0)
    now[0] = 12.0
    assert r.poll() == []
    assert r.go() == 1
    assert r.state()["steps"][1]["sent_s"] == 7.0


def test_unvalidated_after_previous_after_a_repeating_step_is_refused() -> None:
    good = script(step("circle", CIRCLE, "at", 0), step("hover", HOVER, "operator"))
    after = good.steps[1].model_copy(
        update={"trigger": good.steps[1].trigger.model_copy(update={"kind": "after_previous"})}
    )
    bad = MissionScript.model_construct(
        format="nemesys-mission-script", version=1, name="x", steps=[good.steps[0], after]
    )
    with pytest.raises(ValueError, match="never completes"):
        ScriptRunner(bad, "auto", completion_s=[None, 30.0])
    with pytest.raises(ValueError, match="2 times for 3 steps"):
        ScriptRunner(three_step(), "auto", completion_s=[1.0, 2.0])


def test_auto_operator_step_waits_for_go() -> None:
    s = script(step("straight", STRAIGHT, "at", 0), step("hover", HOVER, "operator"))
    r = ScriptRunner(s, "auto", completion_s=[STRAIGHT_DONE_S, 30.0])
    assert r.proposed() is None
    assert r.poll(0.0) == [0]
    with pytest.raises(ScriptRunError, match="acknowledgement"):
        r.go()
    r.mark_acknowledged(0)
    assert r.proposed() == 1
    st = r.state()
    assert st["waiting_for"] == "operator"
    assert st["next"]["index"] == 1
    assert st["next"]["pattern"] == "hover"
    assert st["due_s"] is None
    # poll never releases an operator step, even long after the straight is complete
    assert r.poll(100.0) == []
    assert r.poll(2000.0) == []
    assert r.go() == 1
    assert r.proposed() is None
    with pytest.raises(ScriptRunError):
        r.go()


def test_auto_go_refused_for_timed_step() -> None:
    r = runner()
    with pytest.raises(ScriptRunError, match="time"):
        r.go()
    assert r.state()["next"] is None


def test_step_mode_proposes_each_and_only_go_releases() -> None:
    r = runner("step")
    for i in range(3):
        assert r.proposed() == i
        assert r.state()["waiting_for"] == "operator"
        assert r.state()["next"]["index"] == i
        # time passing and completed patterns release nothing in step mode
        assert r.poll(1000.0 * (i + 1)) == []
        assert r.poll(1000.0 * (i + 1) + 500) == []
        assert r.go() == i
        assert r.proposed() is None
        assert r.state()["waiting_for"] == "acknowledgement"
        with pytest.raises(ScriptRunError):
            r.go()
        r.mark_sent(i)
        assert r.state()["steps"][i]["transmitted"]
        r.mark_acknowledged(i)
    assert r.state()["waiting_for"] == "completion"  # the hover flies on after its ack
    r.poll(5000.0)
    assert r.state()["outcome"] == "completed"


def test_failure_stops_the_run() -> None:
    r = runner()
    assert r.poll(0.0) == [0]
    r.mark_sent(0)
    r.mark_failed(0, "timed out: no acknowledgement")
    st = r.state()
    assert not st["running"]
    assert st["outcome"] == "failed"
    assert st["reason"] == "step 1 (straight) failed: timed out: no acknowledgement"
    assert st["steps"][0]["state"] == "failed"
    assert st["waiting_for"] is None
    assert r.poll(100.0) == []
    assert r.proposed() is None
    with pytest.raises(ScriptRunError):
        r.go()
    # a late acknowledgement does not revive the failed step
    r.mark_acknowledged(0)
    assert r.state()["steps"][0]["state"] == "failed"


def test_stop() -> None:
    r = runner("step")
    assert r.go() == 0
    r.stop()
    st = r.state()
    assert not st["running"]
    assert st["outcome"] == "stopped"
    assert st["reason"] == "stopped by the operator"
    assert r.proposed() is None
    r.mark_acknowledged(0)  # the vehicle still answers for what was sent
    assert r.state()["steps"][0]["state"] == "acknowledged"
    assert r.poll(100.0) == []


def test_never_sends_a_step_twice() -> None:
    s = script(
        step("straight", STRAIGHT, "at", 0),
        step("straight", STRAIGHT, "at", 0),
        step("straight", STRAIGHT, "after_previous"),
    )
    r = ScriptRunner(s, "auto", completion_s=[40.0, 40.0, 40.0])
    sent: list[int] = []
    for k in range(200):
        due = r.poll(float(k))
        sent += due
        for i in due:
            r.mark_sent(i)
            r.mark_acknowledged(i)
            r.mark_acknowledged(i)  # a duplicate acknowledgement changes nothing
    assert sent == [0, 1, 2]
    assert r.state()["outcome"] == "completed"
    assert r.state()["completed_s"] == 41.0 + 40.0  # the last straight's send + its 40 s


def test_marks_for_steps_not_handed_out_are_refused() -> None:
    r = runner()
    with pytest.raises(ScriptRunError, match="not been handed out"):
        r.mark_sent(0)
    with pytest.raises(ScriptRunError, match="not been handed out"):
        r.mark_acknowledged(1)
    with pytest.raises(ScriptRunError, match="no step 7"):
        r.mark_failed(7, "x")
    with pytest.raises(ValueError, match="auto"):
        ScriptRunner(three_step(), "manual")  # type: ignore[arg-type]
    with pytest.raises(ScriptRunError, match="no clock"):
        r.poll()


def test_state_is_json_ready() -> None:
    r = runner()
    r.poll(5.0)
    st = json.loads(json.dumps(r.state()))
    assert set(st) >= {"running", "mode", "step", "next", "waiting_for", "steps", "reason"}
    assert st["steps"][0] == {
        "index": 0,
        "pattern": "straight",
        "trigger": "at",
        "t_s": 0.0,
        "state": "sent",
        "transmitted": False,
        "acknowledged_by_vehicle": False,
        "sent_s": 0.0,
        "completion_s": STRAIGHT_DONE_S,
        "completed_s": None,
        "trigger_text": "at 0 s from the run's start",
        "takes_text": "takes 40 s (estimated)",
        "state_text": "sending",
    }
    assert (
        st["summary"]
        == "running (auto): step 1 (straight) is on its way; step 2 (lawnmower) is next"
    )


# --- when the run is over: the last step's pattern completes (issue 20) -----------------

#: The hover as the vehicle decodes it (what its status names as the active command).
HOVER_ACTIVE: dict[str, object] = {
    "pattern": "hover",
    "params": {"duration": 30.0, "depth": 2.0, "heading": 45.0},
}


def status(
    mode: str, t_s: float, active: dict[str, object] | None = HOVER_ACTIVE
) -> dict[str, object]:
    """A vehicle status as the contract has it (only what the verdict reads)."""
    doc: dict[str, object] = {"t_s": t_s, "mode": mode, "pattern": None}
    if active is not None:
        doc["active"] = active
        doc["pattern"] = active["pattern"]
    return doc


#: The straight as the vehicle decodes it.
STRAIGHT_ACTIVE: dict[str, object] = {
    "pattern": "straight",
    "params": dict(decode_frame(encode_frame("straight", STRAIGHT).frame.bits).command.params),
}


def straight_then_hover(clock: Callable[[], float]) -> ScriptRunner:
    """A straight, then a hover on completion; the vehicle reports its status."""
    s = script(step("straight", STRAIGHT, "at", 0), step("hover", HOVER, "after_previous"))
    completion = [STRAIGHT_DONE_S, HOVER_DONE_S]
    return ScriptRunner(s, "auto", completion_s=completion, clock=clock, completion_by="vehicle")


def to_the_last_ack(r: ScriptRunner, vehicle_t_s: float | None = 500.0) -> None:
    """Both steps out: the hover once the vehicle reports the straight complete."""
    assert r.poll(0.0) == [0]
    r.mark_sent(0)
    r.mark_acknowledged(0, vehicle_t_s=vehicle_t_s)
    assert r.poll(STRAIGHT_DONE_S) == []  # estimated complete, but not reported
    r.observe(status("holding", (vehicle_t_s or 0.0) + STRAIGHT_DONE_S, STRAIGHT_ACTIVE))
    assert r.poll() == [1]  # at once, on the run's clock
    r.mark_sent(1)
    r.mark_acknowledged(1, vehicle_t_s=vehicle_t_s)


def test_the_run_completes_when_the_vehicle_reports_the_last_pattern_complete() -> None:
    now = [STRAIGHT_DONE_S]
    r = straight_then_hover(lambda: now[0])
    to_the_last_ack(r)
    st = r.state()
    assert st["running"] and st["waiting_for"] == "completion"
    assert st["summary"] == (
        "running (auto): every step sent; waiting for the vehicle to report step 2 (hover) "
        "complete, expected at 70 s from the run's start by the estimate"
    )
    assert st["expected_s"] == 70.0
    # long past the plan's time, the vehicle still runs the hover: the run waits
    now[0] = 248.0
    assert r.poll() == []
    r.observe(status("running", 740.0))
    assert r.state()["outcome"] == "running"
    r.observe(None)  # no status at all says nothing either
    assert r.running
    now[0] = 249.5
    r.observe(status("holding", 749.5))
    st = r.state()
    assert not st["running"] and st["outcome"] == "completed"
    assert st["completion_by"] == "vehicle" and st["completed_s"] == 249.5
    assert st["summary"] == (
        "completed at 249.5 s from the run's start: the vehicle reported step 2 (hover) complete"
    )
    assert st["steps"][1]["state_text"] == (
        "sent at 40 s from the run's start, acknowledged by the vehicle; completed at 249.5 s "
        "from the run's start, as the vehicle reported"
    )


def test_a_status_of_another_command_ends_the_wait_only_when_newer_than_the_ack() -> None:
    r = straight_then_hover(lambda: 50.0)
    to_the_last_ack(r, vehicle_t_s=540.0)
    straight: dict[str, object] = {"pattern": "straight", "params": {"speed": 0.4}}
    r.observe(status("holding", 539.0, straight))  # before the hover was accepted: stale
    assert r.running
    r.observe(status("holding", 545.0, straight))  # after it: retasked by someone else
    st = r.state()
    assert st["outcome"] == "stopped"
    assert st["reason"] == (
        "step 2 (hover) will not complete: the vehicle runs straight (holding), not this "
        "step's command"
    )


def test_without_active_only_a_newer_status_of_the_pattern_counts() -> None:
    r = straight_then_hover(lambda: 90.0)
    to_the_last_ack(r, vehicle_t_s=540.0)
    hover_only = {"t_s": 540.0, "mode": "holding", "pattern": "hover"}
    r.observe(hover_only)  # not newer than the acceptance: an older hover may be holding
    assert r.running
    r.observe({**hover_only, "t_s": 571.0})
    assert r.state()["outcome"] == "completed"


def test_an_empty_battery_stops_the_wait() -> None:
    r = straight_then_hover(lambda: 60.0)
    to_the_last_ack(r)
    r.observe(status("battery_empty", 560.0))
    assert r.state()["outcome"] == "stopped"
    assert "battery is empty" in (r.reason or "")


def test_a_navigation_fault_stops_the_wait() -> None:
    r = straight_then_hover(lambda: 60.0)
    to_the_last_ack(r)
    r.observe(status("nav_fault", 560.0))
    assert r.state()["outcome"] == "stopped"
    assert "navigation went stale during the hover (nav_fault)" in (r.reason or "")


def test_a_link_that_reports_nothing_completes_each_step_by_the_estimate() -> None:
    s = script(step("straight", STRAIGHT, "at", 0), step("hover", HOVER, "after_previous"))
    r = ScriptRunner(s, "auto", completion_s=[STRAIGHT_DONE_S, 45.0])
    assert r.completion_by == "estimate"
    assert r.poll(0.0) == [0]
    r.mark_acknowledged(0, by_vehicle=False)
    assert r.poll(STRAIGHT_DONE_S - 0.1) == []
    assert r.poll(STRAIGHT_DONE_S + 2.0) == [1]  # on completion: by the estimate
    assert r.state()["steps"][0]["completed_s"] == STRAIGHT_DONE_S  # the estimate's time
    r.mark_sent(1)
    r.mark_acknowledged(1, by_vehicle=False)
    r.observe(status("holding", 9999.0))  # a link that reports nothing: a status decides nothing
    assert r.running
    st = r.state()
    assert st["due_s"] == STRAIGHT_DONE_S + 2.0 + 45.0
    assert st["summary"] == (
        "running (auto): every step sent; step 2 (hover) is estimated to complete at 87 s "
        "from the run's start (the link reports nothing)"
    )
    assert r.poll(STRAIGHT_DONE_S + 46.9) == []
    assert r.poll(STRAIGHT_DONE_S + 60.0) == []
    st = r.state()
    assert st["outcome"] == "completed" and st["completion_by"] == "estimate"
    assert st["completed_s"] == STRAIGHT_DONE_S + 47.0  # the estimate, not the poll's time
    assert st["summary"] == (
        "completed at 87 s from the run's start (estimated): step 2 (hover) completes then by "
        "the estimate; the link reports nothing to confirm it"
    )
    assert st["steps"][1]["state_text"] == (
        "sent at 42 s from the run's start (this link gives no acknowledgement); completed at "
        "87 s from the run's start by the estimate (the link reports nothing)"
    )


def test_a_step_on_completion_waits_for_the_vehicle_to_report_the_previous_one() -> None:
    """Two-way: the hover goes when the vehicle reports the straight complete (the same
    verdict as the run's end), not at the straight's estimated completion; a report that
    the straight will not complete stops the run."""
    now = [0.0]
    r = straight_then_hover(lambda: now[0])
    assert r.poll(0.0) == [0]
    r.mark_sent(0)
    r.mark_acknowledged(0, vehicle_t_s=500.0)
    now[0] = 3 * STRAIGHT_DONE_S  # long past its estimate
    assert r.poll() == []
    st = r.state()
    assert st["waiting_for"] == "completion" and st["due_s"] is None
    assert st["expected_s"] == STRAIGHT_DONE_S
    assert st["summary"] == (
        "running (auto): step 2 (hover) goes when the vehicle reports step 1 (straight) "
        "complete, expected at 40 s from the run's start by the estimate"
    )
    r.observe(status("running", 600.0, STRAIGHT_ACTIVE))  # still flying it
    r.observe({"t_s": 499.0, "mode": "holding", "pattern": "straight"})  # older than the ack
    r.observe(None)
    assert r.poll() == [] and r.running
    now[0] = 130.0
    r.observe(status("holding", 630.0, STRAIGHT_ACTIVE))
    assert r.state()["due_s"] == 130.0
    assert r.poll() == [1]
    st = r.state()
    assert st["steps"][0]["completed_s"] == 130.0
    assert st["steps"][0]["state_text"].endswith(
        "completed at 130 s from the run's start, as the vehicle reported"
    )
    assert st["steps"][1]["sent_s"] == 130.0
    # the same wait, ended by another command: the run stops, naming the step
    r2 = straight_then_hover(lambda: 50.0)
    assert r2.poll(0.0) == [0]
    r2.mark_acknowledged(0, vehicle_t_s=500.0)
    r2.observe(status("running", 510.0, {"pattern": "circle", "params": {}}))
    assert r2.state()["outcome"] == "stopped"
    assert r2.reason == (
        "step 1 (straight) will not complete: the vehicle runs circle (running), not this "
        "step's command"
    )
    assert r2.poll(1000.0) == []
    # and a link that stops reporting: by the estimate, from then on
    r3 = straight_then_hover(lambda: 50.0)
    assert r3.poll(0.0) == [0]
    r3.mark_acknowledged(0, vehicle_t_s=500.0)
    assert r3.poll(STRAIGHT_DONE_S + 1.0) == []
    r3.completion_by = "estimate"
    assert r3.poll(STRAIGHT_DONE_S + 2.0) == [1]


@pytest.mark.parametrize("completion_by", ["vehicle", "estimate"])
def test_a_repeating_last_step_leaves_the_vehicle_running_until_retasked(
    completion_by: CompletionBy,
) -> None:
    s = script(step("hover", HOVER, "at", 0), step("circle", CIRCLE, "after_previous"))
    r = ScriptRunner(
        s,
        "auto",
        completion_s=[HOVER_DONE_S, None],
        completion_by=completion_by,
    )
    assert r.poll(0.0) == [0]
    r.mark_acknowledged(0, vehicle_t_s=500.0)
    r.observe(status("holding", 530.0))  # the hover complete, as reported
    assert r.poll(HOVER_DONE_S) == [1]
    r.mark_acknowledged(1)
    st = r.state()
    assert not st["running"] and st["outcome"] == "until_retasked"
    assert st["completed_s"] is None and st["waiting_for"] is None
    assert st["summary"] == "every step sent: step 2 (circle) is running until retasked"
    assert st["steps"][1]["takes_text"] == "repeats until retasked"


def test_planned_runner_takes_the_estimate_of_the_vehicles_profile() -> None:
    s = script(step("straight", STRAIGHT, "at", 0), step("circle", CIRCLE, "after_previous"))
    # the twin is slower than the straight's 0.4 m/s: the estimate outlasts the plan's clock
    expanded = expand(s, START, None, flown_timing(twin_profile(Limits().max_depth_m)))
    r = ScriptRunner.planned(s, expanded)
    assert r.completion_s == (expanded[0].completion_s, None)  # the circle repeats
    slow, planned = r.completion_s[0], expanded[0].plan.path.duration_s
    assert slow is not None and slow > planned + 10.0
