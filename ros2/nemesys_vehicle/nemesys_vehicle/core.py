"""The vehicle node's logic, free of ROS: frames in, contract messages out.

:class:`VehicleCore` wraps the onboard agent the simulator runs (:mod:`onboard.agent`:
decode -> validate -> replan -> guidance switch -> one acknowledgement per frame) and the same
guidance (:mod:`onboard.guidance`). Inputs:

* :meth:`VehicleCore.on_frame`: one frame's bytes (``/nemesys/frame``, a UInt8MultiArray's data);
* :meth:`VehicleCore.on_serial_bytes`: a raw ME receiver stream, any chunking
  (:class:`nemesys_vehicle.stream.FrameStream` finds the frames);
* :meth:`VehicleCore.on_odometry`: the navigation solution (:class:`Odometry`, ENU);
* :meth:`VehicleCore.on_navsatfix`: a GPS fix (the datum, :mod:`nemesys_vehicle.georef`);
* :meth:`VehicleCore.on_battery_state`: the state of charge;
* the clock ticks :meth:`tick_status`, :meth:`tick_pose`, :meth:`tick_guidance`.

Outputs go to :class:`nemesys_vehicle.messages.Sinks` (and are returned): acknowledgements,
status and datum as JSON-ready dicts (``/nemesys/mission``, ``/nemesys/status``,
``/nemesys/datum``), the pose and the setpoint as PoseStamped dicts (``/nemesys/pose`` in
``map_ned``; the setpoint in ENU or NED, see :func:`nemesys_vehicle.messages.setpoint_msg`).
Every time is ROS time in seconds, passed in by the caller (the node's clock).

**Every frame is acknowledged at once**, never held: with no navigation to plan from (no
odometry yet, odometry older than ``nav_timeout_s``, or no datum yet) a decoded command is
rejected with ``no_navigation`` (Surface is still flown from the last known position). An
acknowledgement made more than the contract's deadline after the frame's receipt says
``late: true``.

**Navigation health**: navigation is valid while the latest odometry is at most
``nav_timeout_s`` old and the vehicle is geo-referenced. Only then is the pose published
(stamped with the odometry's time) and the status's position filled in. When valid navigation
goes stale the vehicle enters the ``nav_fault`` mode: it flies ``nav_fault_action`` (surface,
or hold the last known depth and position) and the active command is suspended; the mode
stays until a command is accepted again (with valid navigation, or a Surface). A commanded
Surface is no fault: it goes on, from the last known position. Setpoints are
published only while the agent has a command (until the first accepted frame the node leaves
the autopilot alone).
"""

from __future__ import annotations

import math
import time
from typing import Any

from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.frames import NedPose
from nemesys_vehicle.georef import Georef
from nemesys_vehicle.messages import (
    Odometry,
    Setpoint,
    Sinks,
    frame_bits,
    pose_msg,
    setpoint_msg,
)
from nemesys_vehicle.stream import FrameStream
from onboard.agent import NoNavigation, OnboardAgent, command_json
from onboard.guidance import Guidance, Reference
from planner import VehicleState
from vehicle_contract.codes import Mode
from vehicle_contract.contract import ACK_DEADLINE_S, DATUM_REPEAT_S

JsonDict = dict[str, Any]


class VehicleCore:
    """A NemeSys's onboard logic behind a ROS 2 node (see the module doc)."""

    def __init__(self, config: VehicleConfig | None = None, sinks: Sinks | None = None) -> None:
        self.config = config or VehicleConfig()
        self.sinks = sinks or Sinks()
        self.guidance = Guidance(self.config.guidance_config())
        self.agent = OnboardAgent(self.guidance, self.config.limits(), self.config.address)
        self.stream = FrameStream(self.config.address)
        self.georef = Georef(self.config)
        self.odometry: Odometry | None = None
        #: State of charge when the vehicle reports one (None: unknown, ``null`` in status).
        self.battery_pct: float | None = None
        self.frames_in = 0
        self.odometry_rejected = 0  # samples with a non-finite value
        self.battery_rejected = 0  # percentages outside 0..1
        #: The fault action being flown ("surface" or "hold"), None when not in nav_fault.
        self.fault: str | None = None
        self.nav_faults = 0
        #: Where the fault action holds: the last known (north, east, depth, heading).
        self._fault_at = (0.0, 0.0, 0.0, 0.0)
        self._nav_was_valid = False
        self._held = False  # guidance's idle hold point is set (the first map_ned pose)
        self._datum_sent_s: float | None = None

    # --- inputs --------------------------------------------------------------------------

    def on_frame(self, data: bytes, t_s: float, receipt_s: float | None = None) -> JsonDict:
        """One received frame (13 bytes; any other length is acknowledged as malformed).

        Returns the acknowledgement (also sent to ``sinks.ack``), made at once.
        ``receipt_s``: ``time.perf_counter()`` at arrival (the agent's decode latency and the
        deadline start there; default now).
        """
        receipt = time.perf_counter() if receipt_s is None else receipt_s
        self.frames_in += 1
        self._check_navigation(t_s)
        navigation = self.navigation(t_s)
        pose = self.map_pose()
        # without a map_ned position the state carries the time only (nothing is planned)
        state = self.state(t_s) if pose is not None else VehicleState(0.0, 0.0, 0.0, t_s=t_s)
        bits, n_bits = frame_bits(bytes(data), self.config.address is not None)
        ack, ref = self.agent.receive(bits, n_bits, state, receipt, navigation)
        if ref is not None:  # accepted and replanned: guidance's first new setpoint, now
            self.fault = None
            ned = NedPose(state.x_m, state.y_m, state.z_m, state.heading_deg)
            self._emit_setpoint(ref, ned, t_s)
        ack["late"] = time.perf_counter() - receipt > ACK_DEADLINE_S
        self.sinks.ack(ack)
        return ack

    def on_serial_bytes(self, data: bytes, t_s: float) -> list[JsonDict]:
        """Bytes from a serial ME receiver (any chunking): one acknowledgement per frame the
        receiver synchronised on, decoded or not (see :mod:`nemesys_vehicle.stream`)."""
        receipt = time.perf_counter()
        return [self.on_frame(frame, t_s, receipt) for frame in self.stream.feed(data)]

    def on_odometry(self, odometry: Odometry) -> bool:
        """A navigation sample; False (and ignored) if a value is not finite."""
        if not odometry.is_finite():
            self.odometry_rejected += 1
            return False
        self.odometry = odometry
        self._hold_first_pose()
        self._check_navigation(odometry.t_s)  # valid from now: its going stale is a fault
        return True

    def on_navsatfix(self, t_s: float, lat_deg: float, lon_deg: float, fixed: bool) -> bool:
        """A GPS fix (``fixed``: its status says it has one). Used only while the vehicle is
        not yet geo-referenced, with fresh odometry at the surface (depth at most
        ``fix_max_depth_m``); True when it placed ``map_ned`` (the datum is published then)."""
        odometry = self.odometry
        if not fixed or self.georef.referenced or odometry is None:
            return False
        if t_s - odometry.t_s > self.config.nav_timeout_s:
            return False
        if odometry.depth_m > self.config.fix_max_depth_m:
            return False
        try:
            placed = self.georef.on_fix(lat_deg, lon_deg, odometry.enu(), t_s)
        except ValueError:  # a latitude or longitude out of range: no fix
            return False
        if placed:
            self._hold_first_pose()
            self._check_navigation(t_s)
            self._publish_datum(t_s)
        return placed

    def on_battery(self, battery_pct: float | None) -> None:
        """The state of charge in percent, 0..100 (None: unknown).

        Raises:
            ValueError: not a number within 0..100.
        """
        if battery_pct is not None and not 0.0 <= battery_pct <= 100.0:
            raise ValueError(f"battery_pct must be within 0..100, got {battery_pct!r}")
        self.battery_pct = battery_pct

    def on_battery_state(self, fraction: float) -> bool:
        """``sensor_msgs/BatteryState.percentage``: 0..1, NaN when not measured (unknown).
        A value outside 0..1 is ignored and counted (``battery_rejected``): False."""
        if math.isnan(fraction):
            self.battery_pct = None
            return True
        if not 0.0 <= fraction <= 1.0:
            self.battery_rejected += 1
            return False
        self.battery_pct = 100.0 * fraction
        return True

    # --- clock ticks ---------------------------------------------------------------------

    def tick_status(self, t_s: float) -> JsonDict:
        """The status message (contract schema ``status``). Without valid navigation the
        position, depth, heading and speed are unknown: ``null``, as the contract asks. The
        datum goes out with it when due (set, or :data:`DATUM_REPEAT_S` since the last)."""
        self._check_navigation(t_s)
        valid = self.navigation(t_s) is None
        pose = self.map_pose() if valid else None
        odometry = self.odometry
        active = self.agent.active
        status: JsonDict = {
            "t_s": t_s,
            "x_m": pose.x_north_m if pose is not None else None,
            "y_m": pose.y_east_m if pose is not None else None,
            "depth_m": pose.z_down_m if pose is not None else None,
            "heading_deg": pose.heading_deg if pose is not None else None,
            "speed_mps": odometry.speed_mps if odometry is not None and valid else None,
            "battery_pct": self.battery_pct,
            "mode": Mode.NAV_FAULT.value if self.fault is not None else self.guidance.mode.value,
            "pattern": active.pattern if active is not None else None,
            "active": command_json(active.command) if active is not None else None,
            "nav_valid": valid,
            "nav_age_s": max(0.0, t_s - odometry.t_s) if odometry is not None else None,
            "frame_input": "receiver" if self.config.frame_input == "serial" else "topic",
            "recent_acks": self.agent.recent_acks(t_s),
        }
        if self.config.address is not None:  # a fleet's vehicle says which it is
            status["address"] = self.config.address
        self.sinks.status(status)
        sent = self._datum_sent_s
        if sent is None or t_s - sent >= DATUM_REPEAT_S or t_s < sent:
            self._publish_datum(t_s)
        return status

    def tick_pose(self, t_s: float) -> JsonDict | None:
        """The pose in ``map_ned``, stamped with the odometry's time; None (nothing sent)
        without valid navigation."""
        self._check_navigation(t_s)
        pose = self.map_pose()
        if self.navigation(t_s) is not None or pose is None or self.odometry is None:
            return None
        msg = pose_msg(self.odometry.t_s, pose)
        self.sinks.pose(msg)
        return msg

    def tick_guidance(self, t_s: float) -> Setpoint | None:
        """One guidance step from the latest odometry; the setpoint (None, and nothing
        published, before the first accepted command). In ``nav_fault``: the fault action's
        setpoint, from the last known position."""
        self._check_navigation(t_s)
        pose = self.map_pose()
        if pose is None or self.agent.active is None:
            return None
        if self.fault is not None:
            north_m, east_m, depth_m, heading_deg = self._fault_at
            if self.fault == "surface":
                depth_m = 0.0
            mode = Mode.NAV_FAULT.value
            setpoint = Setpoint(t_s, north_m, east_m, depth_m, heading_deg, 0.0, True, mode)
            self._publish_setpoint(setpoint)
            return setpoint
        # (stale navigation without a fault: a commanded Surface; guidance surfaces from the
        # last known position, which is all surfacing needs)
        ref = self.guidance.update(pose.x_north_m, pose.y_east_m, pose.z_down_m, t_s)
        return self._emit_setpoint(ref, pose, t_s)

    # --- navigation ----------------------------------------------------------------------

    def navigation(self, t_s: float) -> NoNavigation | None:
        """None while navigation is valid at ``t_s``; else why not (the ``no_navigation``
        rejection's detail, and whether there is a last known position to surface from)."""
        odometry = self.odometry
        if odometry is None:
            return NoNavigation("no navigation yet: no odometry has arrived", last_known=False)
        age_s = t_s - odometry.t_s
        if age_s > self.config.nav_timeout_s:
            return NoNavigation(
                f"navigation stale: the last odometry is {age_s:.1f} s old (nav_timeout_s "
                f"{self.config.nav_timeout_s:g})",
                last_known=self.georef.referenced,
            )
        if not self.georef.referenced:
            return NoNavigation(self.georef.waiting_for(), last_known=False)
        return None

    def map_pose(self) -> NedPose | None:
        """The latest odometry in ``map_ned`` (None: no odometry, or not geo-referenced)."""
        if self.odometry is None or not self.georef.referenced:
            return None
        return self.georef.to_map(self.odometry.enu())

    def state(self, t_s: float) -> VehicleState:
        """The vehicle as the planner sees it (as :meth:`sim.simulation.Simulation.state`),
        from the latest odometry (the last known position when stale). Depth is at least 0:
        a vehicle afloat whose odometry puts it a little above the surface is at the surface.

        Raises:
            RuntimeError: no map_ned position yet.
        """
        pose = self.map_pose()
        if pose is None or self.odometry is None:
            raise RuntimeError("no map_ned position yet")
        g = self.guidance
        segment = g.segment if g.mode is Mode.RUNNING and g.plan is not None else None
        return VehicleState(
            pose.x_north_m,
            pose.y_east_m,
            max(0.0, pose.z_down_m),
            pose.heading_deg,
            self.odometry.speed_mps,
            t_s,
            segment,
        )

    def _check_navigation(self, t_s: float) -> None:
        """Enter ``nav_fault`` when valid navigation has gone stale since the last check."""
        valid = self.navigation(t_s) is None
        active = self.agent.active
        # a commanded Surface goes on as it is (it overrides everything): no fault action
        surfacing = active is not None and active.pattern == "surface" and self.fault is None
        if self._nav_was_valid and not valid and not surfacing:
            pose = self.map_pose()
            if pose is not None:
                self.fault = self.config.nav_fault_action
                self.nav_faults += 1
                self.agent.suspend()
                self._fault_at = (
                    pose.x_north_m,
                    pose.y_east_m,
                    max(0.0, pose.z_down_m),
                    pose.heading_deg,
                )
        self._nav_was_valid = valid

    def _hold_first_pose(self) -> None:
        """Guidance's idle hold point: the first map_ned pose (station keeping there)."""
        pose = self.map_pose()
        if pose is not None and not self._held:
            self._held = True
            self.guidance.hold_here(
                pose.x_north_m, pose.y_east_m, max(0.0, pose.z_down_m), pose.heading_deg
            )

    # --- outputs -------------------------------------------------------------------------

    def _publish_datum(self, t_s: float) -> None:
        msg = self.georef.datum_msg(t_s)
        if msg is not None:
            self._datum_sent_s = t_s
            self.sinks.datum(msg)

    def _publish_setpoint(self, setpoint: Setpoint) -> None:
        frame_id = self.odometry.frame_id if self.odometry is not None else "odom"
        msg = setpoint_msg(setpoint, self.config.setpoint_frame, frame_id, self.georef.origin)
        self.sinks.setpoint(msg)

    def _emit_setpoint(self, ref: Reference, ned: NedPose, t_s: float) -> Setpoint:
        north_m, east_m = self._aim(ref, ned)
        setpoint = Setpoint(
            t_s,
            north_m,
            east_m,
            ref.depth_m,
            math.degrees(ref.course_rad) % 360.0,
            ref.speed_mps,
            ref.vertical,
            self.guidance.mode.value,
        )
        self._publish_setpoint(setpoint)
        return setpoint

    def _aim(self, ref: Reference, ned: NedPose) -> tuple[float, float]:
        """The point guidance aims at (NED). Path following: the line-of-sight point, along
        the commanded course at ``hypot(lookahead, cross-track)`` (exact on a straight
        segment); station keeping (a hover, the path's end while its last depth change is
        flown, after it) and surfacing: the hold point."""
        g = self.guidance
        following = g.mode is Mode.RUNNING and not g.at_end
        if following and g.plan is not None and g.plan.pattern != "hover":
            reach_m = math.hypot(g.config.lookahead_m, g.cross_track_m)
            return (
                ned.x_north_m + reach_m * math.cos(ref.course_rad),
                ned.y_east_m + reach_m * math.sin(ref.course_rad),
            )
        return g.hold[0], g.hold[1]
