"""The simulated NemeSys as a VehicleEndpoint: frames in, acks out, time, status, battery."""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Callable
from typing import Any

import pytest

from codec import DEFAULT_BITRATE_BPS, FRAME_BITS, ParamValue, encode_frame
from sim.channel import ChannelConfig
from sim.environment import CurrentConfig
from sim.simulation import SimConfig, Simulation
from vehicle_contract.codes import Mode
from vehicle_contract.endpoint import FRAME_BYTES, Pose, VehicleEndpoint

LATENCY_KEYS = ("decode_latency_ms", "replan_latency_ms")
STATUS_KEYS = {
    "t_s",
    "x_m",
    "y_m",
    "depth_m",
    "heading_deg",
    "speed_mps",
    "battery_pct",
    "mode",
    "pattern",
    "active",
    "nav_valid",
    "frame_input",
    "recent_acks",
    "link",
}
LINK_KEYS = {
    "frames_in",
    "frames_lost",
    "accepted",
    "rejected",
    "last_frame_t_s",
    "distance_m",
    "range_m",
    "in_range",
    "ber",
}


def _frame(pattern: str, **params: ParamValue) -> bytes:
    return encode_frame(pattern, params).frame.to_bytes()


CIRCLE = _frame("circle", speed=0.2, depth=2, radius=3, direction="cw")
SQUARE = _frame("square", speed=0.2, depth=2.5, side_span=6, direction="ccw")


def _mode(sim: Simulation) -> Mode:
    """The mode now (a call, so the type checker does not narrow it across steps)."""
    return sim.mode


def _without_latency(acks: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{k: v for k, v in a.items() if k not in LATENCY_KEYS} for a in acks]


def _scripted(sim: Simulation) -> tuple[list[Pose], list[dict[str, Any]]]:
    """Two commands, a pose every second for 60 s."""
    poses = []
    acks: list[dict[str, Any]] = []
    sim.submit_frame(CIRCLE)
    for k in range(60):
        if k == 30:
            sim.submit_frame(SQUARE)
        sim.advance(1.0)
        poses.append(sim.pose())
        acks += sim.take_missions()
    return poses, acks


# --- the endpoint contract -------------------------------------------------------------------


def test_simulation_implements_the_vehicle_endpoint_protocol() -> None:
    endpoint: VehicleEndpoint = Simulation()  # checked by mypy
    for name in ("submit_frame", "advance", "take_missions", "pose", "status"):
        assert callable(getattr(endpoint, name))
    assert endpoint.t_s == 0.0
    pose = endpoint.pose()
    assert isinstance(pose, Pose)
    assert (pose.t_s, pose.x_m, pose.y_m, pose.z_m) == (0.0, 0.0, 0.0, 2.0)
    assert FRAME_BYTES == 13 == len(CIRCLE)
    endpoint.submit_frame(CIRCLE)
    endpoint.advance(1.0)
    assert endpoint.t_s == pytest.approx(1.0)
    acks = endpoint.take_missions()
    assert len(acks) == 1
    assert acks[0]["outcome"] == "accepted"
    assert acks[0]["channel_flipped_bits"] == 0
    assert endpoint.status()["mode"] == "running"


def test_pose_follows_the_vehicle() -> None:
    sim = Simulation(SimConfig(start_x_m=1.0, start_y_m=-2.0, start_z_m=3.0, start_heading_deg=30))
    pose = sim.pose()
    assert (pose.x_m, pose.y_m, pose.z_m) == (1.0, -2.0, 3.0)
    assert pose.heading_deg == pytest.approx(30.0)
    sim.submit_frame(CIRCLE)
    sim.advance(20.0)
    pose = sim.pose()
    v = sim.vehicle
    assert (pose.t_s, pose.x_m, pose.y_m, pose.z_m) == (sim.t_s, v.x, v.y, v.z)
    assert (pose.roll_deg, pose.heading_deg) == (v.roll_deg, v.heading_deg)
    assert (pose.x_m, pose.y_m) != (1.0, -2.0)


def test_take_missions_drains() -> None:
    sim = Simulation()
    sim.submit_frame(CIRCLE)
    sim.submit_frame(b"\x00" * 5)
    assert sim.take_missions() == []  # nothing before the next tick
    sim.advance(0.5)
    first = sim.take_missions()
    # the wrong-length message is not transmitted: it is acknowledged at once, ahead of the
    # frame still on the air (2.8 ms of airtime)
    assert [a["outcome"] for a in first] == ["rejected", "accepted"]
    assert [a["seq"] for a in first] == [1, 2]
    assert sim.take_missions() == []
    sim.advance(1.0)
    assert sim.take_missions() == []
    assert len(sim.acks) == 2  # the run keeps every ack


def test_status_has_every_key_and_is_json() -> None:
    sim = Simulation()
    status = sim.status()
    assert set(status) == STATUS_KEYS
    assert set(status["link"]) == LINK_KEYS
    assert status["mode"] == "idle"
    assert status["pattern"] is None
    assert status["link"]["last_frame_t_s"] is None
    assert status["battery_pct"] == 100.0
    sim.submit_frame(CIRCLE)
    sim.advance(30.0)
    status = sim.status()
    json.loads(json.dumps(status))
    assert status["t_s"] == pytest.approx(30.0)
    assert status["mode"] == "running"
    assert status["pattern"] == "circle"
    assert status["depth_m"] == pytest.approx(2.0, abs=0.05)
    assert status["speed_mps"] == pytest.approx(0.2, abs=0.05)
    assert 0.0 <= status["heading_deg"] < 360.0
    assert 99.0 < status["battery_pct"] < 100.0
    link = status["link"]
    assert link["frames_in"] == 1
    assert link["frames_lost"] == 0
    assert (link["accepted"], link["rejected"]) == (1, 0)
    assert link["last_frame_t_s"] == pytest.approx(100 / 36000)  # arrival: airtime
    assert link["distance_m"] == pytest.approx(
        math.sqrt(sim.vehicle.x**2 + sim.vehicle.y**2 + 4.0), abs=0.05
    )
    assert link["range_m"] == 730.0
    assert link["in_range"] is True
    assert link["ber"] == 0.0
    for key in ("t_s", "x_m", "y_m", "depth_m", "heading_deg", "speed_mps", "battery_pct"):
        assert isinstance(status[key], float), key


def test_wrong_length_frame_gives_one_malformed_ack() -> None:
    sim = Simulation()
    sim.submit_frame(b"\xaa" * 12)
    sim.advance(0.2)
    acks = sim.take_missions()
    assert len(acks) == 1
    ack = acks[0]
    assert ack["outcome"] == "rejected"
    assert ack["reason"] == "malformed"
    assert ack["frame_hex"] is None
    assert "96" in ack["detail"]
    assert "channel_flipped_bits" not in ack  # it never went on the air
    link = sim.status()["link"]
    assert (link["frames_in"], link["frames_lost"], link["rejected"]) == (1, 0, 1)
    assert sim.mode is Mode.IDLE


# --- determinism ----------------------------------------------------------------------------


def test_same_seed_same_run() -> None:
    cfg = SimConfig(
        seed=7,
        channel=ChannelConfig(ber=0.01),
        current=CurrentConfig(east_mps=0.02, speed_sigma_mps=0.01, time_constant_s=20.0),
    )
    poses_a, acks_a = _scripted(Simulation(cfg))
    poses_b, acks_b = _scripted(Simulation(cfg))
    assert poses_a == poses_b
    assert _without_latency(acks_a) == _without_latency(acks_b)
    assert len(acks_a) == 2


def test_different_seed_different_noise() -> None:
    poses_a, _acks_a = _scripted(Simulation(SimConfig(seed=1)))
    poses_b, _acks_b = _scripted(Simulation(SimConfig(seed=2)))
    assert poses_a != poses_b  # depth-sensor noise differs
    # but it is noise: both fly the same pattern to within centimetres
    for a, b in zip(poses_a, poses_b, strict=True):
        assert math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) < 0.2
        assert a.z_m == pytest.approx(b.z_m, abs=0.03)


def test_different_seed_different_channel_errors() -> None:
    flips = []
    for seed in (1, 2):
        sim = Simulation(SimConfig(seed=seed, channel=ChannelConfig(ber=0.05)))
        for _ in range(30):
            sim.submit_frame(CIRCLE)
            sim.advance(0.2)
        flips.append([a["channel_flipped_bits"] for a in sim.take_missions()])
    assert flips[0] != flips[1]


def test_reset_restores_the_start() -> None:
    cfg = SimConfig(seed=4, start_x_m=1.0, start_z_m=1.5, record_hz=1.0)
    sim = Simulation(cfg)
    first = _scripted(sim)
    assert sim.track
    sim.reset()
    assert sim.t_s == 0.0
    assert sim.steps == 0
    assert sim.pose() == Pose(0.0, 1.0, 0.0, 1.5, 0.0, 0.0)
    assert sim.mode is Mode.IDLE
    assert sim.agent.active is None
    assert sim.acks == []
    assert sim.track == []
    assert sim.take_missions() == []
    assert sim.battery.soc_pct == 100.0
    link = sim.status()["link"]
    assert (link["frames_in"], link["frames_lost"], link["accepted"]) == (0, 0, 0)
    assert link["last_frame_t_s"] is None
    again = _scripted(sim)
    assert again[0] == first[0]
    assert _without_latency(again[1]) == _without_latency(first[1])


def test_reset_with_a_new_config() -> None:
    sim = Simulation()
    sim.advance(5.0)
    sim.reset(SimConfig(start_z_m=4.0))
    assert sim.config.start_z_m == 4.0
    assert sim.pose().z_m == 4.0
    assert sim.t_s == 0.0


# --- time ------------------------------------------------------------------------------------


def test_advance_moves_time_by_whole_physics_steps() -> None:
    sim = Simulation()
    sim.advance(1.0)
    assert sim.t_s == pytest.approx(1.0)
    assert sim.steps == 50
    for _ in range(10):
        sim.advance(0.1)
    assert sim.t_s == pytest.approx(2.0)
    assert sim.steps == 100
    sim.advance(0.04)
    assert sim.steps == 102
    sim.advance(0.0)
    assert sim.steps == 102
    sim.run_until(10.0)
    assert sim.t_s == pytest.approx(10.0)
    assert sim.steps == 500
    cfg = SimConfig(physics_hz=100.0, guidance_hz=20.0)
    fast = Simulation(cfg)
    fast.advance(1.0)
    assert fast.steps == 100
    assert fast.t_s == pytest.approx(1.0)


def test_advance_carries_partial_steps_over() -> None:
    slow = Simulation()
    for _ in range(100):
        slow.advance(0.009)  # e.g. the server's 20 ms tick at time_scale 0.45
    assert slow.t_s == pytest.approx(0.9, abs=0.02)
    fast = Simulation()
    for _ in range(100):
        fast.advance(0.011)
    assert fast.t_s == pytest.approx(1.1, abs=0.02)


# --- the channel -----------------------------------------------------------------------------


def test_ack_arrives_after_airtime_and_delay() -> None:
    delay = 0.5
    sim = Simulation(SimConfig(channel=ChannelConfig(delay_s=delay)))
    sim.advance(1.03)
    sent = sim.t_s
    sim.submit_frame(CIRCLE)
    arrival = sent + FRAME_BITS / DEFAULT_BITRATE_BPS + delay
    sim.run_until(arrival - 0.02)
    assert sim.take_missions() == []
    assert sim.mode is Mode.IDLE
    sim.advance(0.5)
    acks = sim.take_missions()
    assert len(acks) == 1
    t_ack = acks[0]["t_s"]
    assert t_ack >= arrival
    # handled on the first physics step after it arrives, not the next guidance tick
    assert t_ack < arrival + 1.0 / sim.config.physics_hz + 1e-9
    assert sim.status()["link"]["last_frame_t_s"] == pytest.approx(arrival)


def test_frame_beyond_range_is_lost_without_ack_and_changes_nothing() -> None:
    cfg = SimConfig(channel=ChannelConfig(range_m=1.0), start_z_m=2.0)
    sim = Simulation(cfg)
    twin = Simulation(cfg)
    assert sim.status()["link"]["in_range"] is False
    sim.submit_frame(CIRCLE)
    sim.advance(20.0)
    twin.advance(20.0)
    assert sim.take_missions() == []
    assert sim.acks == []
    link = sim.status()["link"]
    assert link["frames_in"] == 1
    assert link["frames_lost"] == 1
    assert (link["accepted"], link["rejected"]) == (0, 0)
    assert link["last_frame_t_s"] is None
    assert link["distance_m"] == pytest.approx(2.0, abs=0.05)
    assert sim.mode is Mode.IDLE
    assert sim.agent.active is None
    assert sim.pose() == twin.pose()


def test_noisy_link_corrects_some_frames_rejects_others_and_rejects_change_nothing() -> None:
    sim = Simulation(SimConfig(seed=3, channel=ChannelConfig(ber=0.02)))
    encoded = [encode_frame("hover", duration=600, depth=2, heading=h) for h in (0, 90)]
    by_heading = {e.command.params["heading"]: e.command for e in encoded}
    expected = None  # the command the vehicle should be running
    acks: list[dict[str, Any]] = []
    for k in range(200):
        sim.submit_frame(encoded[k % 2].frame.to_bytes())
        sim.advance(0.2)
        new = sim.take_missions()
        assert len(new) == 1  # no loss configured: every frame is acknowledged
        ack = new[0]
        if ack["outcome"] == "accepted":
            # never miscorrected into some other command
            assert ack["command"]["pattern"] == "hover"
            expected = by_heading[ack["command"]["params"]["heading"]]
        active = sim.agent.active
        assert (active.command if active is not None else None) == expected
        assert ack["active"] == (
            None
            if expected is None
            else {"pattern": "hover", "pattern_id": 6, "params": dict(expected.params)}
        )
        acks.append(ack)
    accepted = [a for a in acks if a["outcome"] == "accepted"]
    rejected = [a for a in acks if a["outcome"] == "rejected"]
    assert any(a["corrected_bits"] > 0 for a in accepted)
    assert any(a["corrected_bits"] == 2 for a in accepted)
    assert len(rejected) > 10
    assert {a["reason"] for a in rejected} <= {"no_sync", "uncorrectable", "crc_mismatch"}
    assert sum(a["channel_flipped_bits"] for a in acks) > 200
    link = sim.status()["link"]
    assert (link["accepted"], link["rejected"]) == (len(accepted), len(rejected))
    assert link["ber"] == 0.02


# --- battery ---------------------------------------------------------------------------------


def test_empty_battery_stops_the_thrusters_and_the_vehicle_floats_up() -> None:
    sim = Simulation(SimConfig(battery_start_h=7.35, start_z_m=2.0))
    assert 0.0 < sim.battery.soc_pct < 1.0
    sim.submit_frame(_frame("circle", speed=0.2, depth=3, radius=3, direction="cw"))
    sim.advance(5.0)
    assert _mode(sim) is Mode.RUNNING
    while _mode(sim) is not Mode.BATTERY_EMPTY:
        sim.advance(1.0)
        assert sim.t_s < 300.0
    assert sim.status()["mode"] == "battery_empty"
    assert sim.status()["battery_pct"] == 0.0
    sim.advance(0.2)
    assert sim.vehicle.tc == (0.0, 0.0, 0.0, 0.0)
    depths = []
    for _ in range(60):
        sim.advance(1.0)
        depths.append(sim.vehicle.z)
        assert sim.vehicle.tc == (0.0, 0.0, 0.0, 0.0)
    assert all(b <= a for a, b in itertools.pairwise(depths))
    assert sim.vehicle.z == 0.0
    assert sim.mode is Mode.BATTERY_EMPTY
    # a new command is still acknowledged, but nothing moves
    sim.submit_frame(_frame("hover", duration=60, depth=2, heading=0))
    sim.advance(10.0)
    assert sim.take_missions()[-1]["outcome"] == "accepted"
    assert sim.vehicle.tc == (0.0, 0.0, 0.0, 0.0)
    assert sim.vehicle.z == 0.0


# --- configuration ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: SimConfig(physics_hz=50.0, guidance_hz=15.0), "physics_hz"),
        (lambda: SimConfig(physics_hz=10.0, guidance_hz=20.0), "physics_hz"),
        (lambda: SimConfig(physics_hz=0.0), "physics_hz"),
        (lambda: SimConfig(guidance_hz=math.nan), "guidance_hz"),
        (lambda: SimConfig(start_z_m=-0.5), "start_z_m"),
    ],
)
def test_sim_config_validation(make: Callable[[], SimConfig], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        make()


def test_valid_rates_are_accepted() -> None:
    cfg = SimConfig(physics_hz=100.0, guidance_hz=100.0, start_z_m=0.0)
    assert cfg.physics_hz == cfg.guidance_hz


def test_battery_start_is_validated() -> None:
    with pytest.raises(ValueError, match="start_h"):
        Simulation(SimConfig(battery_start_h=-1.0))
