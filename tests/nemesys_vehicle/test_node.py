"""node.py holds no logic (checked on its syntax tree), and its wiring against fake rclpy.

The real rclpy is not installable here: what runs below is node.py against the stand-ins of
``fake_rclpy`` (publishers, subscriptions, timers, QoS, parameters as it declares them).
"""

from __future__ import annotations

import array
import ast
import json
import os
import time
from pathlib import Path
from typing import Any

import pytest

import nemesys_vehicle
from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.core import VehicleCore
from tests.nemesys_vehicle import fake_rclpy
from tests.nemesys_vehicle.helpers import AT_DATUM, CIRCLE, frame_bytes
from vehicle_contract.contract import (
    DATUM_TOPIC,
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    topic,
)
from vehicle_contract.names import topic_names
from vehicle_contract.payloads import validate_ack, validate_datum, validate_status

NODE_PY = Path(nemesys_vehicle.__file__).parent / "node.py"

#: Syntax that is logic: none of it anywhere in node.py's functions.
LOGIC = (
    ast.For,
    ast.AsyncFor,
    ast.While,
    ast.ListComp,
    ast.SetComp,
    ast.DictComp,
    ast.GeneratorExp,
    ast.BinOp,
    ast.AugAssign,
    ast.IfExp,
    ast.BoolOp,
    ast.UnaryOp,
    ast.Lambda,
    ast.Match,
)


def _functions() -> dict[str, ast.FunctionDef]:
    tree = ast.parse(NODE_PY.read_text(encoding="utf-8"))
    out: dict[str, ast.FunctionDef] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    out[f"{node.name}.{item.name}"] = item
        elif isinstance(node, ast.FunctionDef) and node.col_offset == 0:
            out[node.name] = node
    return out


def _walk(fn: ast.FunctionDef) -> list[ast.AST]:
    """The function's code (not its signature: ``list[str] | None`` is no arithmetic)."""
    return [node for stmt in fn.body for node in ast.walk(stmt)]


def _body(fn: ast.FunctionDef) -> list[ast.stmt]:
    body = fn.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        return body[1:]  # the docstring
    return body


def _dotted(expr: ast.expr) -> str:
    if isinstance(expr, ast.Attribute):
        return f"{_dotted(expr.value)}.{expr.attr}"
    if isinstance(expr, ast.Name):
        return expr.id
    if isinstance(expr, ast.Call):
        return f"{_dotted(expr.func)}()"
    return "?"


# --- static: no logic in node.py -----------------------------------------------------------


def test_node_py_has_no_loops_arithmetic_or_branches_beyond_the_input_choice() -> None:
    functions = _functions()
    assert {"qos_profile", "main", "VehicleNode.__init__"} <= set(functions)
    for name, fn in functions.items():
        for node in _walk(fn):
            assert not isinstance(node, LOGIC), f"{name}: {type(node).__name__} line {node.lineno}"
            if isinstance(node, ast.Try):
                assert name == "main", f"{name}: try"
    ifs = [n for fn in functions.values() for n in _walk(fn) if isinstance(n, ast.If)]
    assert len(ifs) == 1  # topic or serial
    assert ifs[0] in _walk(functions["VehicleNode.__init__"])
    test = ifs[0].test
    assert isinstance(test, ast.Compare)
    assert _dotted(test.left) == "config.frame_input"
    compares = [n for fn in functions.values() for n in _walk(fn) if isinstance(n, ast.Compare)]
    assert compares == [test]


def test_every_callback_is_one_line_delegating_to_the_core() -> None:
    functions = _functions()
    init_refs = {
        _dotted(n)
        for n in ast.walk(functions["VehicleNode.__init__"])
        if isinstance(n, ast.Attribute)
    }
    callbacks = {k: v for k, v in functions.items() if k.split(".")[-1].startswith("_on_")}
    assert len(callbacks) == 8
    for name, fn in callbacks.items():
        body = _body(fn)
        assert len(body) == 1, name
        stmt = body[0]
        assert isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Call), name
        target = _dotted(stmt.value.func)
        assert target.startswith("self.core."), (name, target)
        assert hasattr(VehicleCore, target.removeprefix("self.core.")), target
        assert f"self.{fn.name}" in init_refs, f"{name} is never registered"
    publishers = {k: v for k, v in functions.items() if ".__init__" not in k and "_publish_" in k}
    assert len(publishers) == 5
    for name, fn in publishers.items():
        body = _body(fn)
        assert len(body) == 1, name
        stmt = body[0]
        assert isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Call), name
        assert _dotted(stmt.value.func).endswith("_pub.publish"), name
        assert f"self.{fn.name}" in init_refs, f"{name} is never handed to the core"


def test_node_py_builds_the_core_and_takes_conversions_from_convert() -> None:
    tree = ast.parse(NODE_PY.read_text(encoding="utf-8"))
    imported = {
        (n.module, a.name) for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names
    }
    assert ("nemesys_vehicle.core", "VehicleCore") in imported
    assert ("nemesys_vehicle.convert", "odometry_from_msg") in imported
    assert ("nemesys_vehicle.convert", "fill_pose_stamped") in imported


# --- the wiring, against fake rclpy --------------------------------------------------------


def _odometry_msg(east_m: float, north_m: float, up_m: float) -> Any:
    msg = fake_rclpy.OdometryMsg()
    msg.header.frame_id = "odom"
    msg.pose.pose.position.x, msg.pose.pose.position.y = east_m, north_m
    msg.pose.pose.position.z = up_m
    msg.twist.twist.linear.x = 0.3  # facing east (identity orientation), 0.3 m/s ahead
    return msg


def _qos(qos: Any) -> tuple[str, str, int]:
    assert qos.history == "keep_last"
    return (qos.reliability, qos.durability, qos.depth)


def test_topic_mode_wiring(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fake_rclpy.Node, "overrides", {})
    with fake_rclpy.installed(monkeypatch) as fake:
        node = fake.node.VehicleNode()
        assert node.name == "nemesys_vehicle"
        assert node.params == dict(VehicleConfig.parameter_defaults())
        assert node.core.config == VehicleConfig()
        # subscriptions: the frame topic RELIABLE + TRANSIENT_LOCAL, as the contract says
        assert set(node.subscriptions) == {FRAME_TOPIC, "/odom", "/fix", "/battery_state"}
        frame_type, on_frame, frame_qos = node.subscriptions[FRAME_TOPIC]
        assert frame_type is fake_rclpy.UInt8MultiArray
        assert _qos(frame_qos) == ("reliable", "transient_local", 10)
        odom_type, on_odometry, odom_qos = node.subscriptions["/odom"]
        assert odom_type is fake_rclpy.OdometryMsg
        assert _qos(odom_qos)[:2] == ("best_effort", "volatile")
        fix_type, on_fix, fix_qos = node.subscriptions["/fix"]
        assert fix_type is fake_rclpy.NavSatFix
        assert _qos(fix_qos)[:2] == ("best_effort", "volatile")
        battery_type, on_battery, _ = node.subscriptions["/battery_state"]
        assert battery_type is fake_rclpy.BatteryState
        # publishers, with the contract's QoS
        pubs = node.publishers
        contract_topics = (MISSION_TOPIC, STATUS_TOPIC, POSE_TOPIC, DATUM_TOPIC)
        assert set(pubs) == {*contract_topics, "/nemesys/setpoint"}
        for name in contract_topics:
            q = topic(name).qos
            assert _qos(pubs[name].qos) == (q.reliability.value, q.durability.value, q.depth)
        assert _qos(pubs[DATUM_TOPIC].qos) == ("reliable", "transient_local", 1)
        assert _qos(pubs["/nemesys/setpoint"].qos) == ("reliable", "volatile", 1)
        periods = sorted(p for p, _ in node.timers)
        assert periods == pytest.approx([0.05, 0.1, 0.5])
        timers = {round(p, 6): cb for p, cb in node.timers}
        # a status before any odometry: unknown numbers null, navigation not valid
        timers[0.5]()
        status = json.loads(pubs[STATUS_TOPIC].sent[-1].data)
        assert validate_status(status) == []
        assert (status["depth_m"], status["nav_valid"]) == (None, False)
        # a frame before any odometry: rejected at once, never held
        on_frame(fake_rclpy.UInt8MultiArray(array.array("B", frame_bytes("circle", **CIRCLE))))
        ack = json.loads(pubs[MISSION_TOPIC].sent[-1].data)
        assert validate_ack(ack) == []
        assert (ack["outcome"], ack["reason"], ack["late"]) == ("rejected", "no_navigation", False)
        # odometry at the surface, then the first fix there: the datum, published at once
        on_odometry(_odometry_msg(3.0, 4.0, 0.0))
        assert pubs[DATUM_TOPIC].sent == []
        on_fix(fake_rclpy.NavSatFix(29.5316, -82.3031, status=0))
        datum = json.loads(pubs[DATUM_TOPIC].sent[-1].data)
        assert validate_datum(datum) == []
        assert (datum["lat_deg"], datum["lon_deg"], datum["source"]) == (
            29.5316,
            -82.3031,
            "navsatfix",
        )
        assert datum["odometry_origin"] == {"north_m": -4.0, "east_m": -3.0}
        on_battery(fake_rclpy.BatteryState(0.5))
        # 1 m east and 2 m north of there, 2 m deep
        on_odometry(_odometry_msg(4.0, 6.0, -2.0))
        on_frame(fake_rclpy.UInt8MultiArray(array.array("B", frame_bytes("circle", **CIRCLE))))
        ack = json.loads(pubs[MISSION_TOPIC].sent[-1].data)
        assert validate_ack(ack) == []
        assert ack["outcome"] == "accepted"
        assert ack["t_s"] == pytest.approx(1_700_000_000.25)
        assert (ack["from"]["x_m"], ack["from"]["y_m"], ack["from"]["z_m"]) == (2.0, 1.0, 2.0)
        assert ack["from"]["heading_deg"] == 90.0
        assert ack["from"]["speed_mps"] == pytest.approx(0.3)
        assert len(pubs["/nemesys/setpoint"].sent) == 1
        timers[0.1]()
        assert len(pubs["/nemesys/setpoint"].sent) == 2
        setpoint = pubs["/nemesys/setpoint"].sent[-1]
        assert setpoint.header.frame_id == "odom"
        assert setpoint.header.stamp.sec == 1_700_000_000
        assert setpoint.header.stamp.nanosec == 250_000_000
        timers[0.05]()
        pose = pubs[POSE_TOPIC].sent[-1]
        assert pose.header.frame_id == "map_ned"
        p = pose.pose.position
        assert (p.x, p.y, p.z) == (2.0, 1.0, 2.0)
        assert all(type(v) is float for v in (p.x, p.y, p.z))
        timers[0.5]()
        status = json.loads(pubs[STATUS_TOPIC].sent[-1].data)
        assert validate_status(status) == []
        assert (status["x_m"], status["y_m"], status["depth_m"]) == (2.0, 1.0, 2.0)
        assert (status["pattern"], status["battery_pct"], status["nav_valid"]) == (
            "circle",
            50.0,
            True,
        )
        assert [a["seq"] for a in status["recent_acks"]] == [1, 2]
        node.destroy_node()
        assert node.destroyed


def test_a_vehicle_namespace_moves_every_contract_topic(monkeypatch: pytest.MonkeyPatch) -> None:
    overrides = {"vehicle_namespace": "auv1", "odometry_topic": "odom"}
    monkeypatch.setattr(fake_rclpy.Node, "overrides", overrides)
    with fake_rclpy.installed(monkeypatch) as fake:
        node = fake.node.VehicleNode()
        names = topic_names("auv1")
        assert names.mission == "/auv1/nemesys/mission"
        assert set(node.publishers) == {
            names.mission,
            names.status,
            names.pose,
            names.datum,
            "/auv1/nemesys/setpoint",
        }
        assert set(node.subscriptions) == {names.frame, "/auv1/odom", "/fix", "/battery_state"}


def test_serial_mode_wiring_reads_a_pty(monkeypatch: pytest.MonkeyPatch) -> None:
    master, slave = os.openpty()
    overrides = {
        "frame_input": "serial",
        "serial_url": os.ttyname(slave),
        "setpoint_frame": "ned",
        "odometry_topic": "/vehicle/odom",
        **AT_DATUM,  # the navigation starts at the datum: no fix needed
    }
    monkeypatch.setattr(fake_rclpy.Node, "overrides", overrides)
    try:
        with fake_rclpy.installed(monkeypatch) as fake:
            node = fake.node.VehicleNode()
            # no frame topic
            assert set(node.subscriptions) == {"/vehicle/odom", "/fix", "/battery_state"}
            periods = sorted(p for p, _ in node.timers)
            assert periods == pytest.approx([0.02, 0.05, 0.1, 0.5])
            poll = next(cb for p, cb in node.timers if abs(p - 0.02) < 1e-9)
            node.subscriptions["/vehicle/odom"][1](_odometry_msg(0.0, 0.0, -1.0))
            poll()  # opens the port (raw mode) before anything is written
            assert node._serial.is_open
            os.write(master, b"\x00\x00" + frame_bytes("circle", **CIRCLE))
            mission = node.publishers[MISSION_TOPIC].sent
            deadline = time.monotonic() + 5.0
            while not mission and time.monotonic() < deadline:
                poll()
                time.sleep(0.005)
            assert len(mission) == 1
            assert json.loads(mission[0].data)["outcome"] == "accepted"
            setpoint = node.publishers["/nemesys/setpoint"].sent[-1]
            assert setpoint.header.frame_id == "map_ned"
            node.destroy_node()
            assert not node._serial.is_open
    finally:
        os.close(slave)
        os.close(master)


def test_main_spins_and_shuts_down(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fake_rclpy.Node, "overrides", {})
    with fake_rclpy.installed(monkeypatch) as fake:
        fake.node.main([])
        assert fake.calls == ["init", "spin", "shutdown"]
        assert fake_rclpy.Node.created[-1].destroyed

        def interrupted(node: Any) -> None:
            raise KeyboardInterrupt

        monkeypatch.setattr(fake.node.rclpy, "spin", interrupted)
        fake.node.main([])
        assert fake.calls[-1] == "shutdown"
