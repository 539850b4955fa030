"""The lifecycle table: every event from every state it may happen in, and refusals."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import pytest

from backend.commands.lifecycle import (
    ON_ITS_WAY,
    RETRYABLE,
    TERMINAL,
    TRANSITIONS,
    Event,
    IllegalTransition,
    State,
    advance,
)
from backend.commands.manager import MIN_SURFACE_COPIES, SURFACE_DELIVERY_TARGET
from backend.mission_log.store import FINAL_STATES, STATES
from codec import copies_for, frame_success_probability

#: Every legal (state, event) -> state, written out independently of the table.
EXPECTED = {
    ("queued", "copy_sent"): "transmitted",
    ("transmitted", "copy_sent"): "transmitted",
    ("transmitted", "copies_out"): "sent",
    ("queued", "no_copy_left"): "failed",
    ("queued", "accepted"): "acknowledged",
    ("transmitted", "accepted"): "acknowledged",
    ("queued", "rejected"): "rejected",
    ("transmitted", "rejected"): "rejected",
    ("transmitted", "ack_timeout"): "timed_out",
    ("queued", "superseded"): "superseded",
    ("transmitted", "superseded"): "superseded",
    ("queued", "interrupted"): "interrupted",
    ("transmitted", "interrupted"): "interrupted",
}


@pytest.mark.parametrize(("state", "event"), list(itertools.product(State, Event)))
def test_every_state_and_event(state: State, event: Event) -> None:
    expected = EXPECTED.get((state.value, event.value))
    if expected is None:
        with pytest.raises(IllegalTransition, match=event.value):
            advance(state, event)
    else:
        assert advance(state, event) == expected


def test_the_table_is_the_expected_one() -> None:
    derived = {(str(s), str(e)): str(t) for e, (sources, t) in TRANSITIONS.items() for s in sources}
    assert derived == EXPECTED


def test_state_sets() -> None:
    assert set(ON_ITS_WAY) == {"queued", "transmitted"}
    assert frozenset(State) - ON_ITS_WAY == TERMINAL
    assert set(RETRYABLE) == {"interrupted", "timed_out", "failed", "rejected", "superseded"}
    assert RETRYABLE < TERMINAL
    # sent and acknowledged are ends nobody retries: the command got through, as far as known
    assert {"sent", "acknowledged"} == set(TERMINAL - RETRYABLE)
    assert set(FINAL_STATES) == {str(s) for s in TERMINAL} and len(STATES) == 9


def test_illegal_transition_names_the_allowed_states() -> None:
    with pytest.raises(IllegalTransition) as err:
        advance("sent", Event.SUPERSEDED)
    assert "sent" in str(err.value) and "queued, transmitted" in str(err.value)


def test_a_retry_is_no_transition() -> None:
    """A retry is a new command (the command service's): no event takes a terminal record
    anywhere, so nothing ended is ever sent again under its old id."""
    for _event, (sources, _target) in TRANSITIONS.items():
        assert not sources & TERMINAL


def test_docs_api_draws_every_transition() -> None:
    """docs/api.md's table and mermaid diagram name exactly the table's transitions."""
    doc = (Path(__file__).resolve().parents[3] / "docs" / "api.md").read_text()
    section = doc[doc.index("### The command lifecycle") : doc.index("### Link health")]
    rows = re.findall(r"^\| (\w+) \| (\w+) \| (\w+) \| .+ \|$", section, re.M)
    table = {(s, e): t for s, e, t in rows if (s, e) != ("from", "event")}
    assert table == EXPECTED
    arrows = re.findall(r"^    (\w+) --> (\w+): (\w+)", section, re.M)
    assert {(s, e): t for s, t, e in arrows} == EXPECTED


def test_docs_copies_table_is_the_arithmetic() -> None:
    doc = (Path(__file__).resolve().parents[3] / "docs" / "api.md").read_text()
    rows = re.findall(r"^\| ([\d.e-]+) \| ([\d.]+) \| (\d+) \| (\d+) \|$", doc, re.M)
    assert len(rows) == 3
    for ber, p1, r, surface in rows:
        b = float(ber)
        assert float(p1) == pytest.approx(frame_success_probability(b), abs=6e-5)
        assert int(r) == copies_for(b, 0.999)
        assert int(surface) == copies_for(b, SURFACE_DELIVERY_TARGET, minimum=MIN_SURFACE_COPIES)
