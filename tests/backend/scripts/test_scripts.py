"""Mission scripts: validation naming the place at fault, preview as the vehicle flies it,
and the onboard export (the run: test_scripts_runner.py; completion: test_scripts_completion.py)."""

from __future__ import annotations

import copy
import math
from typing import Any

import pytest
from pydantic import ValidationError

from backend.scripts.operations import (
    PREVIEW_MAX_POINTS,
    MissionScript,
    ScriptError,
    expand,
    export_onboard,
    flown_timing,
    onboard_csv,
    preview,
)
from codec import decode_frame, encode_frame
from planner import VehicleState, plan

SQUARE: dict[str, float | str] = {"speed": 0.18, "depth": 2, "side_span": 8.03, "direction": "cw"}
CIRCLE: dict[str, float | str] = {"speed": 0.18, "depth": 3, "radius": 5.07, "direction": "cw"}
LAWNMOWER: dict[str, float | str] = {
    "speed": 0.3,
    "depth": 3,
    "sweep_length": 10,
    "lane_spacing": 2,
    "laps": 2,
}
STRAIGHT: dict[str, float | str] = {"speed": 0.4, "depth": 2.5, "duration": 40, "heading": 90}
HOVER: dict[str, float | str] = {"duration": 30, "depth": 2, "heading": 45}
START = VehicleState(0.0, 0.0, 2.0, heading_deg=0.0, speed_mps=0.18, t_s=500.0)


def step(pattern: str, params: dict[str, float | str], kind: str, t_s: float | None = None) -> Any:
    trigger: dict[str, Any] = {"kind": kind}
    if t_s is not None:
        trigger["t_s"] = t_s
    return {"pattern": pattern, "params": dict(params), "trigger": trigger}


def doc(*steps: Any) -> dict[str, Any]:
    return {
        "format": "nemesys-mission-script",
        "version": 1,
        "name": "pod patrol",
        "steps": list(steps),
    }


def script(*steps: Any) -> MissionScript:
    return MissionScript.model_validate(doc(*steps))


POD = doc(step("square", SQUARE, "at", 0), step("circle", CIRCLE, "at", 120))


def errors_of(data: Any) -> dict[str, str]:
    """``{"steps.1.params.radius": message}`` for every error."""
    with pytest.raises(ValidationError) as info:
        MissionScript.model_validate(data)
    return {".".join(map(str, e["loc"])): e["msg"] for e in info.value.errors()}


# --- validation -------------------------------------------------------------------------


def test_valid_script_parses_with_real_types() -> None:
    s = MissionScript.model_validate(POD)
    assert s.steps[1].trigger.kind == "at"
    assert s.steps[1].trigger.t_s == 120.0
    assert s.steps[0].params["direction"] == "cw"
    assert isinstance(s.steps[0].params["speed"], float)


def test_round_trip_json() -> None:
    s = script(
        step("square", SQUARE, "at", 0),
        step("circle", CIRCLE, "operator"),
        step("surface", {}, "at", 500),
        step("hover", HOVER, "after_previous"),
    )
    again = MissionScript.model_validate_json(s.model_dump_json())
    assert again == s
    assert again.steps[1].trigger.t_s is None


def test_out_of_range_param_names_step_and_param() -> None:
    data = copy.deepcopy(POD)
    data["steps"][1]["params"]["radius"] = -1
    errors = errors_of(data)
    assert list(errors) == ["steps.1.params.radius"]
    assert "radius" in errors["steps.1.params.radius"]
    assert "0 to 750 m" in errors["steps.1.params.radius"]


def test_error_message_contains_location() -> None:
    data = copy.deepcopy(POD)
    data["steps"][1]["params"]["radius"] = 3000
    with pytest.raises(ValidationError) as info:
        MissionScript.model_validate(data)
    assert "steps.1.params.radius" in str(info.value)


def test_unknown_pattern_names_the_pattern_field() -> None:
    data = copy.deepcopy(POD)
    data["steps"][1]["pattern"] = "figure_eight"
    errors = errors_of(data)
    assert list(errors) == ["steps.1.pattern"]
    assert "figure_eight" in errors["steps.1.pattern"]


def test_missing_and_unknown_params_are_named() -> None:
    data = copy.deepcopy(POD)
    del data["steps"][0]["params"]["depth"]
    data["steps"][1]["params"]["colour"] = "red"
    errors = errors_of(data)
    assert set(errors) == {"steps.0.params.depth", "steps.1.params.colour"}


def test_boolean_param_rejected_not_read_as_one() -> None:
    data = copy.deepcopy(POD)
    data["steps"][0]["params"]["depth"] = True
    assert list(errors_of(data)) == ["steps.0.params.depth"]


def test_bad_choice_names_param() -> None:
    data = copy.deepcopy(POD)
    data["steps"][1]["params"]["direction"] = "sideways"
    errors = errors_of(data)
    assert "cw" in errors["steps.1.params.direction"]


def test_at_trigger_needs_time() -> None:
    data = copy.deepcopy(POD)
    del data["steps"][1]["trigger"]["t_s"]
    errors = errors_of(data)
    assert list(errors) == ["steps.1.trigger.t_s"]
    assert "'at'" in errors["steps.1.trigger.t_s"]


def test_other_triggers_take_no_time() -> None:
    data = copy.deepcopy(POD)
    data["steps"][1]["trigger"] = {"kind": "after_previous", "t_s": 10}
    assert list(errors_of(data)) == ["steps.1.trigger.t_s"]


def test_negative_time_and_unknown_kind() -> None:
    data = copy.deepcopy(POD)
    data["steps"][1]["trigger"]["t_s"] = -5
    assert list(errors_of(data)) == ["steps.1.trigger.t_s"]
    data["steps"][1]["trigger"] = {"kind": "whenever"}
    assert list(errors_of(data)) == ["steps.1.trigger.kind"]


def test_at_times_must_not_decrease() -> None:
    data = doc(
        step("straight", STRAIGHT, "at", 100),
        step("hover", HOVER, "after_previous"),
        step("circle", CIRCLE, "at", 50),
    )
    errors = errors_of(data)
    assert list(errors) == ["steps.2.trigger.t_s"]
    assert "before step 1's 100 s" in errors["steps.2.trigger.t_s"]  # numbered as the page
    # equal times are allowed
    data["steps"][2]["trigger"]["t_s"] = 100
    MissionScript.model_validate(data)


def test_first_step_cannot_follow_a_previous_one() -> None:
    data = doc(step("square", SQUARE, "after_previous"))
    assert list(errors_of(data)) == ["steps.0.trigger.kind"]
    MissionScript.model_validate(doc(step("square", SQUARE, "operator")))


def test_several_errors_reported_together() -> None:
    data = copy.deepcopy(POD)
    data["steps"][0]["params"]["speed"] = 9
    data["steps"][1]["trigger"] = {"kind": "operator", "t_s": 3}
    assert set(errors_of(data)) == {"steps.0.params.speed", "steps.1.trigger.t_s"}


def test_header_fields() -> None:
    for key, value, where in (
        ("format", "other", "format"),
        ("version", 2, "version"),
        ("name", "", "name"),
        ("name", "x" * 81, "name"),
        ("steps", [], "steps"),
    ):
        data = copy.deepcopy(POD)
        data[key] = value
        assert list(errors_of(data)) == [where], key
    data = copy.deepcopy(POD)
    data["steps"] = [step("hover", HOVER, "at", 0)] * 101
    assert list(errors_of(data)) == ["steps"]
    data = copy.deepcopy(POD)
    data["steps"][0]["colour"] = "red"
    assert list(errors_of(data)) == ["steps.0.colour"]


# --- preview ----------------------------------------------------------------------------


def test_preview_second_step_starts_where_square_is_at_120_s() -> None:
    s = MissionScript.model_validate(POD)
    pv = preview(s, START)
    assert [p.pattern for p in pv.steps] == ["square", "circle"]
    sq, ci = pv.steps
    assert sq.t_start_s == 0.0
    assert ci.t_start_s == 120.0
    assert sq.t_end_s == 120.0
    # the square as the vehicle flies it, from the snapped frame: where the estimate (not the
    # plan's own clock) has the vehicle at 120 s
    square_cmd = decode_frame(encode_frame("square", SQUARE).frame.bits).command
    square_plan = plan(square_cmd, START)
    flies = expand(s, START)[0].timing
    assert flies.to_plan_s(120.0) != pytest.approx(120.0, abs=1.0)  # the clocks differ
    at = square_plan.path.sample(flies.to_plan_s(120.0))
    assert (ci.start.x_m, ci.start.y_m, ci.start.z_m) == pytest.approx((at.x_m, at.y_m, at.z_m))
    assert ci.start.heading_deg == pytest.approx(at.course_deg)
    assert ci.start.t_s == 120.0
    # and the circle's plan starts there (its join begins at the vehicle)
    circle_plan = expand(s, START)[1].plan
    assert (circle_plan.path.xs[0], circle_plan.path.ys[0]) == pytest.approx((at.x_m, at.y_m))
    # the square has not finished a lap by 120 s, so the cut is mid-pattern
    assert square_plan.path.duration_s > 120.0


def test_preview_shows_snapped_values() -> None:
    pv = preview(MissionScript.model_validate(POD), START)
    sq, ci = pv.steps
    assert sq.params["side_span"] == 8.0
    assert sq.requested["side_span"] == 8.03
    assert ci.params["radius"] == 5.0
    changed = {n.field: (n.requested, n.sent) for n in ci.snaps if n.changed}
    assert changed == {"radius": (5.07, 5.0)}
    assert sq.hex == encode_frame("square", SQUARE).frame.hex
    assert len(sq.bits) == 100


def test_preview_plans_the_snapped_command() -> None:
    # the circle's orbit radius is the sent 5.0 m, not the requested 5.07 m
    s = MissionScript.model_validate(POD)
    circle = expand(s, START)[1].plan
    cx, cy = circle.origin
    path = circle.path
    body = range(path.body_start, len(path))
    radii = [math.hypot(path.xs[i] - cx, path.ys[i] - cy) for i in body]
    assert max(abs(r - 5.0) for r in radii) < 0.05


def test_combined_path_is_continuous_in_time() -> None:
    pv = preview(MissionScript.model_validate(POD), START)
    p = pv.path
    n = len(p.t_s)
    assert n == len(p.x_m) == len(p.y_m) == len(p.z_m)
    assert p.t_s[0] == 0.0
    assert all(p.t_s[i + 1] > p.t_s[i] for i in range(n - 1))
    # the plan's path timed as the vehicle is estimated to fly it: it passes each corner a
    # lookahead early (it cuts it), so along the drawn corner it seems a little faster than
    # its 0.18 m/s and the planner's 0.05 m/s ramp; never a jump
    for i in range(n - 1):
        dt = p.t_s[i + 1] - p.t_s[i]
        horizontal = math.hypot(p.x_m[i + 1] - p.x_m[i], p.y_m[i + 1] - p.y_m[i])
        assert horizontal <= 1.5 * 0.18 * dt + 0.01, i
        assert abs(p.z_m[i + 1] - p.z_m[i]) <= 1.5 * 0.05 * dt + 0.01, i
    # the retask point is shared: step 1 starts at the point at 120 s
    k = p.step_start[1]
    assert p.step_start[0] == 0
    assert p.t_s[k] == 120.0
    ci = pv.steps[1].start
    assert (p.x_m[k], p.y_m[k]) == pytest.approx((ci.x_m, ci.y_m), abs=1e-3)
    # the last (repeating) step is shown for one lap
    assert p.repeats
    assert p.t_s[-1] == pytest.approx(pv.duration_s, abs=1e-3)
    assert pv.duration_s == pytest.approx(120.0 + pv.steps[1].duration_s)


def test_repeating_pattern_is_unrolled_until_the_next_step() -> None:
    # a small fast circle runs many laps before the straight at 600 s
    small: dict[str, float | str] = {"speed": 0.5, "depth": 2, "radius": 2, "direction": "ccw"}
    s = script(step("circle", small, "at", 0), step("straight", STRAIGHT, "at", 600))
    pv = preview(s, START)
    assert pv.steps[0].duration_s < 100.0
    k = pv.path.step_start[1]
    assert pv.path.t_s[k] == 600.0
    centre = expand(s, START)[0].plan.origin
    laps = [
        math.hypot(x - centre[0], y - centre[1])
        for x, y, t in zip(pv.path.x_m[:k], pv.path.y_m[:k], pv.path.t_s[:k], strict=True)
        if t > 100.0
    ]
    assert len(laps) > 20
    assert all(abs(r - 2.0) < 0.05 for r in laps)
    assert not pv.path.thinned


def test_long_repeat_is_thinned_and_bounded() -> None:
    tiny: dict[str, float | str] = {"speed": 1.0, "depth": 2, "radius": 1, "direction": "cw"}
    s = script(step("circle", tiny, "at", 0), step("surface", {}, "at", 80_000))
    pv = preview(s, START)
    assert pv.path.thinned
    assert len(pv.path.t_s) <= PREVIEW_MAX_POINTS + 10
    assert pv.path.t_s[pv.path.step_start[1]] == 80_000.0
    assert pv.steps[1].start.t_s == 80_000.0


def test_after_previous_on_finite_patterns_triggers_at_their_end() -> None:
    s = script(
        step("lawnmower", LAWNMOWER, "at", 0),
        step("straight", STRAIGHT, "after_previous"),
        step("hover", HOVER, "after_previous"),
    )
    pv = preview(s, START)
    ex = expand(s, START)
    mow, line, hov = pv.steps
    assert not mow.repeats and not line.repeats
    assert line.t_start_s == pytest.approx(mow.duration_s)
    assert hov.t_start_s == pytest.approx(line.t_start_s + line.duration_s)
    assert mow.t_end_s == pytest.approx(line.t_start_s)
    mow_path = ex[0].plan.path
    assert (line.start.x_m, line.start.y_m, line.start.z_m) == pytest.approx(
        (mow_path.xs[-1], mow_path.ys[-1], mow_path.zs[-1])
    )
    assert line.start.speed_mps == 0.0  # the lawnmower is complete: holding
    line_path = ex[1].plan.path
    assert (hov.start.x_m, hov.start.y_m) == pytest.approx((line_path.xs[-1], line_path.ys[-1]))
    assert pv.warnings == []
    assert pv.duration_s == pytest.approx(hov.t_start_s + 30.0)
    texts = [e.text for e in pv.timeline]
    assert any(t.startswith("lawnmower completes") for t in texts)
    assert any(t.startswith("hover completes") for t in texts)
    assert [e.t_s for e in pv.timeline] == sorted(e.t_s for e in pv.timeline)


def test_operator_go_after_repeating_pattern_assumes_one_lap() -> None:
    s = script(step("circle", CIRCLE, "at", 10), step("straight", STRAIGHT, "operator"))
    pv = preview(s, START)
    ci, line = pv.steps
    assert ci.repeats and ci.completion_s is None
    assert ci.warnings == []
    assert len(line.warnings) == 1
    assert "no completion to wait for" in line.warnings[0]
    assert "one lap" in line.warnings[0]
    assert line.t_start_s == pytest.approx(10.0 + ci.duration_s)
    # one lap flown: the straight starts where the lap ends
    lap = expand(s, START)[0].plan.path
    assert (line.start.x_m, line.start.y_m) == pytest.approx((lap.xs[-1], lap.ys[-1]))
    assert line.start.speed_mps > 0.0  # still circling
    assert pv.warnings == [f"step 2: {line.warnings[0]}"]


def test_operator_step_assumes_previous_completes_and_warns() -> None:
    s = script(step("straight", STRAIGHT, "at", 0), step("hover", HOVER, "operator"))
    pv = preview(s, START)
    line, hov = pv.steps
    assert hov.t_start_s == pytest.approx(line.duration_s)
    assert any("operator" in w for w in hov.warnings)


def test_at_before_previous_start_is_sent_right_after_it() -> None:
    s = script(
        step("straight", STRAIGHT, "at", 0),
        step("hover", HOVER, "after_previous"),
        step("circle", CIRCLE, "at", 10),
    )
    pv = preview(s, START)
    assert pv.steps[2].t_start_s == pv.steps[1].t_start_s > 10.0
    assert any("as soon as step 2" in w for w in pv.steps[2].warnings)


def test_first_step_later_waits_at_start() -> None:
    s = script(step("hover", HOVER, "at", 30))
    pv = preview(s, START)
    only = pv.steps[0]
    assert only.t_start_s == 30.0
    assert (only.start.x_m, only.start.y_m, only.start.z_m) == (0.0, 0.0, 2.0)
    assert only.start.t_s == 30.0
    assert pv.path.t_s[0] == 0.0
    assert pv.path.step_start == [1]


def test_current_plan_keeps_the_anchor_and_is_flown_first() -> None:
    cmd = encode_frame("circle", {"speed": 0.2, "depth": 2, "radius": 4, "direction": "cw"})
    current = plan(decode_frame(cmd.frame.bits).command, VehicleState(10.0, 0.0, 2.0, t_s=400.0))
    s = script(step("square", SQUARE, "at", 50))
    ex = expand(s, START, current)
    assert ex[0].plan.anchor == current.anchor
    flies = flown_timing(None)(current)  # where the estimate has the vehicle on it
    at = current.path.sample(flies.to_plan_s(START.t_s + 50.0 - current.t0_s))
    assert (ex[0].state.x_m, ex[0].state.y_m) == pytest.approx((at.x_m, at.y_m))
    pv = preview(s, START, current)
    assert pv.path.t_s[pv.path.step_start[0]] == 50.0


def test_unflyable_step_names_step_and_param() -> None:
    s = script(
        step("hover", HOVER, "at", 0),
        step("circle", {**CIRCLE, "radius": 0}, "after_previous"),
    )
    with pytest.raises(ScriptError) as info:
        preview(s, START)
    assert info.value.loc == ("steps", 1, "params", "radius")
    assert info.value.errors()[0]["loc"] == ["steps", 1, "params", "radius"]
    assert "steps.1.params.radius" in str(info.value)


def test_preview_is_json_ready() -> None:
    pv = preview(MissionScript.model_validate(POD), START)
    data = pv.model_dump(mode="json")
    assert set(data) >= {"steps", "path", "timeline", "duration_s", "warnings"}
    assert set(data["steps"][0]) >= {
        "index",
        "pattern",
        "params",
        "hex",
        "bits",
        "t_start_s",
        "duration_s",
        "waypoints",
        "warnings",
    }
    assert data["steps"][0]["waypoints"] > 4


# --- export -----------------------------------------------------------------------------


def test_export_frames_match_encoder_and_times() -> None:
    s = script(
        step("square", SQUARE, "at", 0),
        step("circle", CIRCLE, "at", 120),
        step("lawnmower", LAWNMOWER, "operator"),
        step("surface", {}, "at", 900),
    )
    out = export_onboard(s, START)
    pv = preview(s, START)
    assert out["format"] == "nemesys-onboard-script"
    assert out["version"] == 1
    assert out["name"] == "pod patrol"
    frames = out["frames"]
    assert [f["pattern"] for f in frames] == ["square", "circle", "lawnmower", "surface"]
    for f, st, src in zip(frames, pv.steps, s.steps, strict=True):
        enc = encode_frame(src.pattern, src.params)
        assert f["hex"] == enc.frame.hex
        assert f["bits"] == enc.frame.bits
        assert f["t_s"] == pytest.approx(st.t_start_s, abs=1e-3)
    assert [f["t_s"] for f in frames[:2]] == [0.0, 120.0]
    assert "note" not in frames[0]
    assert "operator" in frames[2]["note"]
    assert frames[3]["t_s"] == 900.0 and "note" not in frames[3]


@pytest.mark.parametrize("fmt", ["json", "csv"])
def test_export_refuses_on_completion_naming_the_step_and_the_estimated_time(fmt: str) -> None:
    # issue 20: "on completion" became a fixed t = 20 s without a word; the onboard script
    # holds only timed frames, so the export refuses it, in JSON and in CSV alike
    s = script(
        step("square", SQUARE, "at", 0),
        step("lawnmower", LAWNMOWER, "at", 120),
        step("surface", {}, "after_previous"),
    )
    mow = expand(s, START)[1]
    with pytest.raises(ScriptError) as info:
        export_onboard(s, START) if fmt == "json" else onboard_csv(s, START)
    err = info.value
    assert err.loc == ("steps", 2, "trigger", "kind")
    assert err.errors()[0]["type"] == "onboard_completion_trigger"
    assert err.message.startswith(
        "step 3 waits for step 2 (lawnmower) to complete, but an onboard script holds only "
        "timed frames"
    )
    done_s = 120.0 + (mow.completion_s or 0.0)
    assert err.message.endswith(
        f"Give step 3 a time ('at'): step 2 is estimated to complete at {done_s:.1f} s from "
        "the run's start (its plan flown on the vehicle's profile)"
    )


def test_onboard_csv() -> None:
    s = MissionScript.model_validate(POD)
    lines = onboard_csv(s, START).splitlines()
    assert lines[0] == "t_s,pattern,hex"
    assert lines[1] == f"0.000,square,{encode_frame('square', SQUARE).frame.hex}"
    assert lines[2] == f"120.000,circle,{encode_frame('circle', CIRCLE).frame.hex}"
    assert len(lines) == 3
