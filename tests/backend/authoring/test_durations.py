"""One duration story (issue 20): for every pattern at in-profile speeds, the preview's estimate
within 20 % of the prediction, and the prediction within 5 % of the training simulator's own run
of the same command from the same state; where the plan's clock, the estimate and the prediction
still differ by more than 20 %, the reason in words."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.authoring.durations import DIFFER, estimate_notes, flown, prediction_notes, rates_of
from backend.authoring.profile import VehicleProfile, twin_profile
from bench.durations import run_s
from codec import decode_frame, encode_frame
from planner import Plan, VehicleState, plan
from sim.simulation import Simulation
from tests.backend.authoring.test_predict import _paused_mid_circle
from tests.backend.conftest import AUTH, console_of, wait_until

TWIN = twin_profile(100.0)
#: In-profile: below the twin's 0.19 m/s top speed.
SPEED = 0.15
#: Every pattern but surface, as a retask of the training vehicle 60 s into its circle (the
#: conftest's CIRCLE: 0.18 m/s, 3 m deep, 5 m radius): a join from a moving vehicle, depth
#: changes both ways, the orbits around the circle's anchor. Each is done within the
#: prediction's 600 s horizon.
RETASKS: dict[str, dict[str, Any]] = {
    "straight": {"speed": SPEED, "depth": 5, "duration": 90, "heading": 90},
    "square": {"speed": SPEED, "depth": 4, "side_span": 8, "direction": "ccw"},
    "lawnmower": {"speed": SPEED, "depth": 2, "sweep_length": 10, "lane_spacing": 3, "laps": 1},
    "circle": {"speed": SPEED, "depth": 4, "radius": 7, "direction": "ccw"},
    "spiral": {
        "speed": SPEED,
        "depth": 3,
        "initial_radius": 2,
        "final_radius": 6,
        "loops": 2,
        "direction": "cw",
    },
    "helix": {
        "speed": SPEED,
        "start_depth": 3,
        "end_depth": 6,
        "radius": 5,
        "turns": 2,
        "direction": "cw",
    },
    "hover": {"duration": 60, "depth": 5, "heading": 90},
    "box_orbit": {"speed": SPEED, "depth": 3, "radius": 5, "direction": "cw", "laps": 1},
}
#: The straight the issue reports: 2 -> 12.5 m in 75 s, at 0.18 and at 0.5 m/s.
REPORTED = {"speed": 0.18, "depth": 12.5, "duration": 75, "heading": 0}


def _three(client: TestClient, pattern: str, params: dict[str, Any]) -> tuple[float, float, Any]:
    """(estimate, prediction, run) durations (s) of one command from the paused vehicle."""
    console = console_of(client)
    assert client.portal is not None and console.sim is not None
    reference: Simulation = client.portal.call(copy.deepcopy, console.sim)
    body = {"pattern": pattern, "params": params}
    preview = client.post("/api/preview", json=body)
    assert preview.status_code == 200, preview.text
    pred = client.post("/api/predict", json=body)
    assert pred.status_code == 200, pred.text
    doc = pred.json()
    assert doc["outcome"] == "accepted" and doc["completes"] is True, doc
    est = preview.json()["estimate"]["duration_s"]
    assert doc["estimate_duration_s"] == pytest.approx(est)  # the same estimate in both
    return est, doc["duration_s"], run_s(reference, pattern, params)


@pytest.mark.training
@pytest.mark.parametrize("pattern", list(RETASKS))
def test_estimate_prediction_and_the_simulators_run_agree(client: TestClient, pattern: str) -> None:
    """The run is the training simulator itself (a deep copy of the paused one, its random
    generators included), sent the frame and timed by the bench's rule, which reads only
    guidance's mode, its segment and the true depth (not the simulator's completion record
    the prediction uses)."""
    _paused_mid_circle(client)
    three = _three(client, pattern, RETASKS[pattern])
    est, predicted, run = three
    assert run is not None, three
    assert predicted == pytest.approx(run, rel=0.05), three
    assert est == pytest.approx(predicted, rel=DIFFER), three


@pytest.mark.training
def test_a_drifting_current_runs_on_in_the_prediction_as_in_the_simulator(
    client: TestClient,
) -> None:
    """The training current drifts (a Gauss-Markov process): the prediction runs the
    simulator's own process on from its state, so it times the run as the simulator will;
    the estimate is for still water, and the note says so where that is 20 % off."""
    r = client.put(
        "/api/training/current",
        json={"north_mps": -0.08, "speed_sigma_mps": 0.02, "direction_sigma_deg": 20},
        headers=AUTH,
    )
    assert r.status_code == 200, r.text
    _paused_mid_circle(client)
    params = {"speed": SPEED, "depth": 3, "duration": 60, "heading": 0}  # into the current
    est, predicted, run = _three(client, "straight", params)
    assert run is not None and predicted == pytest.approx(run, rel=0.05)
    assert predicted > (1 + DIFFER) * est  # slowed by the water
    doc = client.post("/api/predict", json={"pattern": "straight", "params": params}).json()
    (note,) = doc["duration_notes"]
    assert note.startswith("the water current (0.0") and "still water" in note
    assert any("drifts" in a for a in doc["assumptions"])


@pytest.mark.training
def test_the_reported_straight_now_tells_one_story(client: TestClient) -> None:
    """The issue's numbers from the training start: estimate 210 s, plan 210 s, prediction
    80 s, the vehicle at 12.5 m after ~165 s. Now the estimate and the prediction are within
    20 % of each other and the prediction within 5 % of the run; the plan's clock is 20 %
    away and the preview says why."""
    console = console_of(client)
    sim = console.sim
    assert sim is not None
    r = client.put("/api/training/time_scale", json={"time_scale": 0}, headers=AUTH)
    assert r.status_code == 200

    def paused_state_shown() -> bool:  # the console's telemetry is the paused vehicle's
        times = ((console.hub.pose or {}).get("t_s"), (console.hub.status or {}).get("t_s"))
        return all(isinstance(t, float) and abs(t - sim.t_s) < 1e-6 for t in times)

    wait_until(paused_state_shown, what="telemetry of the paused vehicle")
    for speed in (0.18, 0.5):
        params = {**REPORTED, "speed": speed}
        three = _three(client, "straight", params)
        est, predicted, run = three
        assert run is not None and predicted == pytest.approx(run, rel=0.05), three
        assert est == pytest.approx(predicted, rel=DIFFER), three
        preview = client.post("/api/preview", json={"pattern": "straight", "params": params})
        notes = preview.json()["estimate"]["duration_notes"]
        assert any("flown in place at the end" in n for n in notes)
        if speed == 0.5:
            assert notes[0] == (
                f"the vehicle cannot hold 0.5 m/s: its top speed is {TWIN.top_speed_mps:.2f} m/s"
            )
        else:
            assert not any("cannot hold" in n for n in notes)


# --- the notes, without a simulator ------------------------------------------------------


def _plan(pattern: str, params: dict[str, Any], state: VehicleState | None = None) -> Plan:
    cmd = decode_frame(encode_frame(pattern, params).frame.bits).command
    return plan(cmd, state or VehicleState(0.0, 0.0, 2.0))


def test_an_in_profile_level_pattern_needs_no_note() -> None:
    p = _plan("straight", {"speed": SPEED, "depth": 2, "duration": 120, "heading": 0})
    est, flight = flown(p, TWIN)
    assert est.duration_s == pytest.approx(120.0, abs=1.0)
    assert estimate_notes(p, est, flight, TWIN) == []


def test_a_small_square_is_flown_inside_its_corners_and_the_note_says_so() -> None:
    p = _plan("square", {"speed": SPEED, "depth": 2, "side_span": 2, "direction": "cw"})
    est, flight = flown(p, TWIN)
    assert est.duration_s < est.planned_duration_s / (1 + DIFFER)
    (note, *_) = estimate_notes(p, est, flight, TWIN)
    assert note.startswith("guidance cuts corners and tight turns (it steers 1.5 m ahead): ")


def test_an_ascent_left_for_the_end_is_timed_at_the_ascent_rate() -> None:
    p = _plan(
        "straight",
        {"speed": SPEED, "depth": 2, "duration": 30, "heading": 0},
        VehicleState(0.0, 0.0, 12.0),
    )
    est, flight = flown(p, TWIN)
    assert TWIN.ascent_rate_mps is not None
    in_place = 10.0 - 30 * 0.05  # the plan ramps 1.5 m as it goes, the rest at the end
    assert flight.depth_wait_s == pytest.approx(in_place / TWIN.ascent_rate_mps, abs=2.0)
    notes = estimate_notes(p, est, flight, TWIN)
    assert any(
        n.startswith("the last 8.5 m up are flown in place at the end, at 0.11") for n in notes
    )


def test_an_unknown_profile_flies_as_planned() -> None:
    """A real vehicle without figures: the commanded speed, the planner's depth rates."""
    unknown = VehicleProfile(None, None, None, 100.0, None, "settings")
    assert rates_of(unknown).top_speed_mps is None and rates_of(None).descent_mps is None
    p = _plan("straight", {**REPORTED, "speed": 0.5})
    est, _ = flown(p, unknown)
    assert est.duration_s == pytest.approx(est.planned_duration_s, rel=0.02)


def test_prediction_notes_name_the_current_or_the_model() -> None:
    assert prediction_notes(100.0, 110.0, (0.0, 0.0)) == []
    assert prediction_notes(None, 110.0, (0.1, 0.0)) == []
    (water,) = prediction_notes(200.0, 100.0, (0.0, -0.1))
    assert water.startswith("the water current (0.10 m/s towards 270 deg)")
    (model,) = prediction_notes(200.0, 100.0, (0.0, 0.0))
    assert "200 s" in model and "100 s" in model


def test_a_path_the_model_cannot_finish_falls_back_to_the_plans_clock_and_says_so() -> None:
    """2 m/s on a 1 m circle, for a vehicle of unknown figures, from 20 m deep (the plan flies
    laps until its depth ramp ends): it cannot turn that tightly (at most 20 deg/s: a 5.7 m
    radius), guidance never wraps into the lap; the estimate is the plan's own, and the note
    says why."""
    unknown = VehicleProfile(None, None, None, 100.0, None, "settings")
    params = {"speed": 2.0, "depth": 2, "radius": 1, "direction": "cw"}
    p = _plan("circle", params, VehicleState(-30.0, 20.0, 20.0, 200.0))
    est, flight = flown(p, unknown)
    assert flight.done_s is None
    assert est.duration_s == est.planned_duration_s
    (note,) = estimate_notes(p, est, flight, unknown)
    assert note.startswith("guidance on the vehicle's profile does not finish this path")
