"""What the page says of a script, in words (backend/scripts/labels.py): durations read
"takes 127.8 s", times "at 20 s from the run's start", triggers and states in the operator's
words, never the JSON's identifiers (issue 20: "completion 127.778 s", "time into the dive",
"trigger after_previous, transmitted yes")."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from backend.scripts.labels import at_time, seconds, takes, trigger_text
from backend.scripts.operations import TRIGGER_WORDS, ScriptRunner, preview
from tests.backend.scripts.test_scripts import (
    CIRCLE,
    HOVER,
    LAWNMOWER,
    START,
    STRAIGHT,
    script,
    step,
)

REPO = Path(__file__).resolve().parents[3]
#: Words that are the JSON's, not the operator's.
IDENTIFIERS = re.compile(r"after_previous|transmitted|_s\b|into the dive|completion_s|\btrue\b")


def test_durations_and_times_read_differently() -> None:
    assert seconds(127.778) == "127.8 s"
    assert seconds(20.0) == "20 s"
    assert seconds(19.96) == "20 s"
    assert takes(127.778) == "takes 127.8 s"
    assert takes(160.0, estimated=True) == "takes 160 s (estimated)"
    assert takes(160.0, True, 210.0) == "takes 160 s (estimated; 210 s by the plan's own clock)"
    assert takes(160.0, True, 160.04) == "takes 160 s (estimated)"  # reads the same: once
    assert takes(None) == "repeats until retasked"
    assert at_time(20.0) == "at 20 s from the run's start"


def test_triggers_in_the_operators_words() -> None:
    assert trigger_text("at", 60.0) == "at 60 s from the run's start"
    assert trigger_text("after_previous", None) == "after the previous step completes"
    assert trigger_text("operator", None) == "on the operator's go"
    assert TRIGGER_WORDS["at"] == "at a time from the run's start"


def test_the_pages_trigger_list_says_the_same() -> None:
    js = (REPO / "frontend" / "script_format.js").read_text()
    found = re.search(r"const TRIGGERS = \[(.*?)\];", js, re.S)
    assert found is not None, "frontend/script_format.js declares TRIGGERS"
    pairs = dict(re.findall(r'\["([a-z_]+)", "([^"]+)"\]', found.group(1)))
    assert pairs == TRIGGER_WORDS
    assert "into the dive" not in js
    assert "into the dive" not in (REPO / "frontend" / "script.js").read_text()


def test_timeline_and_steps_label_times_from_the_runs_start() -> None:
    s = script(
        step("hover", HOVER, "at", 0),
        step("lawnmower", LAWNMOWER, "after_previous"),
        step("circle", CIRCLE, "at", 400),
    )
    pv = preview(s, START)
    labels = [e.label for e in pv.timeline]
    assert labels[0] == "at 0 s from the run's start: hover starts (at its set time)"
    assert (
        "at 30 s from the run's start: lawnmower retasks the vehicle (after step 1 completes, "
        "estimated)" in labels
    )
    assert "at 400 s from the run's start: circle retasks the vehicle (at its set time)" in labels
    for e in pv.timeline:
        assert e.label == f"{at_time(e.t_s)}: {e.text}"
    mow = pv.steps[1]
    assert mow.timing_text == (
        "starts at 30 s from the run's start (estimated), "
        + takes(mow.completion_s, True, mow.planned_completion_s)
    )
    assert pv.steps[2].timing_text == "starts at 400 s from the run's start, repeats until retasked"


def every_state_of_a_run() -> list[dict[str, Any]]:
    """A run's state at each of its stages, two-way and one-way."""
    states = []
    for by in ("vehicle", "estimate"):
        s = script(
            step("straight", STRAIGHT, "at", 0),
            step("hover", HOVER, "after_previous"),
            step("lawnmower", LAWNMOWER, "operator"),
        )
        r = ScriptRunner(s, "auto", completion_s=[40.0, 30.0, 150.0], completion_by=by)
        states.append(r.state())
        assert r.poll(0.0) == [0]
        states.append(r.state())
        r.mark_sent(0)
        states.append(r.state())
        r.mark_acknowledged(0, by_vehicle=by == "vehicle", vehicle_t_s=10.0)
        states.append(r.state())
        if by == "vehicle":  # the hover goes when the vehicle reports the straight complete
            assert r.poll(40.0) == []
            r.observe({"t_s": 45.0, "mode": "holding", "pattern": "straight"})
        assert r.poll(40.0) == [1]
        r.mark_acknowledged(1, by_vehicle=by == "vehicle", vehicle_t_s=50.0)
        r.poll(41.0)
        states.append(r.state())
        assert r.go(100.0) == 2
        r.mark_acknowledged(2, by_vehicle=by == "vehicle", vehicle_t_s=110.0)
        states.append(r.state())
        if by == "vehicle":
            r.observe({"t_s": 300.0, "mode": "holding", "pattern": "lawnmower"})
        else:
            r.poll(400.0)
        states.append(r.state())
        assert r.state()["outcome"] == "completed"
    return states


@pytest.mark.parametrize("index", range(14))
def test_no_run_text_uses_an_identifier(index: int) -> None:
    st = every_state_of_a_run()[index]
    texts = [st["summary"]] + [
        s[k] for s in st["steps"] for k in ("trigger_text", "takes_text", "state_text")
    ]
    for text in texts:
        assert not IDENTIFIERS.search(text), text


def test_step_states_in_words() -> None:
    states = every_state_of_a_run()
    first = [st["steps"][0]["state_text"] for st in states[:4]]
    assert first == [
        "not sent yet",
        "sending",
        "sent at 0 s from the run's start, waiting for the acknowledgement",
        "sent at 0 s from the run's start, acknowledged by the vehicle",
    ]
    assert (
        states[0]["summary"] == "running (auto): step 1 (straight) goes at 0 s from the run's start"
    )
    assert states[4]["summary"] == "running (auto): step 3 (lawnmower) awaits the operator's go"
    assert states[3]["summary"] == (
        "running (auto): step 2 (hover) goes when the vehicle reports step 1 (straight) "
        "complete, expected at 40 s from the run's start by the estimate"
    )
    assert states[7 + 3]["summary"] == (
        "running (auto): step 2 (hover) goes when step 1 (straight) is estimated to complete "
        "at 40 s from the run's start (the link reports nothing)"
    )
    assert states[4]["steps"][0]["state_text"] == (
        "sent at 0 s from the run's start, acknowledged by the vehicle; completed at 40 s from "
        "the run's start, as the vehicle reported"
    )
    assert states[7 + 4]["steps"][0]["state_text"] == (
        "sent at 0 s from the run's start (this link gives no acknowledgement); completed at "
        "40 s from the run's start by the estimate (the link reports nothing)"
    )
    assert [s["trigger_text"] for s in states[0]["steps"]] == [
        "at 0 s from the run's start",
        "after the previous step completes",
        "on the operator's go",
    ]
    assert [s["takes_text"] for s in states[0]["steps"]] == [
        "takes 40 s (estimated)",
        "takes 30 s (estimated)",
        "takes 150 s (estimated)",
    ]
