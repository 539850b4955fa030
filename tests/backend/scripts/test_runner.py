"""The script run's state machine: triggers on the run clock, acknowledgements, the
operator's go, failures, and completion by the plan (never by waiting on the vehicle)."""

from __future__ import annotations

import json

import pytest

from backend.scripts.operations import MissionScript, RunMode, ScriptRunError, ScriptRunner, expand
from tests.backend.scripts.test_scripts import (
    CIRCLE,
    HOVER,
    LAWNMOWER,
    START,
    STRAIGHT,
    script,
    step,
)

#: The planned completion times the tests give the runner (s after each step takes effect).
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


def test_after_previous_is_due_the_planned_completion_after_the_previous_send() -> None:
    r = runner()
    assert r.poll(0.0) == [0]
    r.mark_acknowledged(0)
    assert r.poll(62.5) == [1]  # the lawnmower goes out at 62.5 s (a late poll)
    r.mark_sent(1)
    r.mark_acknowledged(1)
    st = r.state()
    assert st["waiting_for"] == "completion"
    assert st["due_s"] == 62.5 + MOW_DONE_S
    # no vehicle report is needed, and none is waited for
    assert r.poll(62.5 + MOW_DONE_S - 0.1) == []
    assert r.poll(62.5 + MOW_DONE_S) == [2]
    assert r.poll(62.5 + MOW_DONE_S + 1) == []
    r.mark_acknowledged(2)
    st = r.state()
    assert not st["running"]
    assert st["outcome"] == "completed"
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
        "state": "sent",
        "transmitted": False,
        "sent_s": 0.0,
        "completion_s": STRAIGHT_DONE_S,
    }
