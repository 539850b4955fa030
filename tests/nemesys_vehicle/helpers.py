"""Shared helpers of the vehicle node tests: odometry samples, frames, ack comparison."""

from __future__ import annotations

import copy
import json
import math
from typing import Any

from codec import GUARD_BITS, ParamValue, encode_frame
from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.core import VehicleCore
from nemesys_vehicle.messages import Odometry, Recorder, frame_bits
from vehicle_contract.payloads import validate_ack

CIRCLE: dict[str, ParamValue] = {"speed": 0.2, "depth": 2, "radius": 3, "direction": "cw"}
#: The agent's wall-clock measurements: present or not, never equal between two runs.
LATENCY_KEYS = ("decode_latency_ms", "replan_latency_ms")
#: A datum for the tests (Lake Wauburg, the console's training site).
DATUM = (29.5316, -82.3031)
#: The navigation starts at the datum: map_ned is the odometry's axes (no fix needed).
AT_DATUM: dict[str, Any] = {
    "datum_source": "parameters",
    "datum_lat_deg": DATUM[0],
    "datum_lon_deg": DATUM[1],
    "odometry_origin_at_datum": True,
}


def odometry(
    t_s: float = 100.0,
    *,
    east_m: float = 10.0,
    north_m: float = 20.0,
    up_m: float = -2.0,
    yaw_enu_deg: float = 0.0,
    speed_mps: float = 0.1,
    frame_id: str = "odom",
) -> Odometry:
    """An ENU odometry sample with a yaw-only orientation."""
    half = math.radians(yaw_enu_deg) / 2.0
    return Odometry(
        t_s,
        east_m,
        north_m,
        up_m,
        0.0,
        0.0,
        math.sin(half),
        math.cos(half),
        speed_mps,
        frame_id,
    )


def frame_bytes(pattern: str, **params: ParamValue) -> bytes:
    return encode_frame(pattern, params).frame.to_bytes()


def bytes_of(frame_value: int) -> bytes:
    """The 13 wire bytes of a 100-bit frame int."""
    return (frame_value << GUARD_BITS).to_bytes(13, "big")


def without_latencies(ack: dict[str, Any]) -> dict[str, Any]:
    """The ack less the latencies and the node's own ``late`` (the agent has none)."""
    return {k: v for k, v in ack.items() if k not in (*LATENCY_KEYS, "late")}


def same_ack(got: dict[str, Any], want: dict[str, Any]) -> bool:
    """Equal but for the latencies, which must be measured in the same places."""
    return without_latencies(got) == without_latencies(want) and all(
        (got[k] is None) == (want[k] is None) for k in LATENCY_KEYS
    )


T0_S = 1_700_000_000.0  # ROS time on a real robot: epoch seconds


def make_core(**config: Any) -> tuple[VehicleCore, Recorder]:
    """A core with that configuration (by default geo-referenced at once: the navigation
    starts at :data:`DATUM`), its outputs recorded."""
    rec = Recorder()
    return VehicleCore(VehicleConfig(**{**AT_DATUM, **config}), rec.sinks()), rec


def circle_codes() -> tuple[int, ...]:
    return encode_frame("circle", CIRCLE).command.codes


def flip(data: bytes, *frame_bits_: int) -> bytes:
    """Flip bits of a packed frame, counted on the wire (0 = the first bit)."""
    out = bytearray(data)
    for pos in frame_bits_:
        out[pos // 8] ^= 0x80 >> (pos % 8)
    return bytes(out)


def no_header(data: bytes) -> bytes:
    return bytes(3) + data[3:]


def receive_checked(core: VehicleCore, rec: Recorder, data: bytes, t_s: float) -> dict[str, Any]:
    """Hand ``data`` to the core; check it gives exactly one ack, the agent's own (a twin of
    the core's agent, given the same bits and state, says the same), valid under the
    contract."""
    twin = copy.deepcopy(core.agent)
    state = core.state(t_s)
    before = len(rec.acks)
    ack = core.on_frame(data, t_s)
    assert ack is not None
    assert len(rec.acks) == before + 1
    assert rec.acks[-1] is ack
    bits, n_bits = frame_bits(data)
    want, _ = twin.receive(bits, n_bits, state)
    assert same_ack(ack, want), (ack, want)
    assert ack["late"] is False
    assert validate_ack(ack) == []
    json.dumps(ack, allow_nan=False)
    return ack


def running_core(**config: Any) -> tuple[VehicleCore, Recorder]:
    """A core flying a circle, some way along it (guidance segment > 0)."""
    core, rec = make_core(**config)
    core.on_odometry(odometry(T0_S))
    ack = receive_checked(core, rec, frame_bytes("circle", **CIRCLE), T0_S)
    assert ack["outcome"] == "accepted"
    active = core.agent.active
    assert active is not None
    path = active.path
    for i in range(path.body_start + 3):
        t_s = T0_S + 1 + i
        core.on_odometry(odometry(t_s, east_m=path.ys[i], north_m=path.xs[i], up_m=-path.zs[i]))
        assert core.tick_guidance(t_s) is not None
    assert core.guidance.segment > 0
    return core, rec


def soon(core: VehicleCore) -> float:
    """A time half a second after the latest odometry (navigation still valid)."""
    assert core.odometry is not None
    return core.odometry.t_s + 0.5
