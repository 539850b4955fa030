"""The console's runtime: everything the app's lifespan owns, and the operations on it.

:class:`Console` starts, in order: the mission log (a dive starts when the vehicle is first
heard: :mod:`backend.dives`), in training mode the
simulated vehicle and its rosbridge server on loopback, the link to the vehicle (the same
rosbridge client a real vehicle gets), the telemetry hub, the command manager and the viser
3D view. The routers only call its methods; nothing starts at import time.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Coroutine, Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from backend.authoring import operations
from backend.authoring.predict import TwinWorker
from backend.authoring.profile import VehicleProfile, profile_for
from backend.belief.model import BelievedPosition
from backend.belief.tracker import Beliefs
from backend.chart.geo import Datum, initial_datum
from backend.chart.gps import GpsFix, GpsReader, Station, parse_gps, station_of
from backend.chart.reach import active_path_doc, with_lat_lon
from backend.chart.tiles import TileSource, open_tiles
from backend.chart.vehicle_datum import DatumWatch
from backend.clock import SYSTEM_CLOCK, Clock
from backend.commands.checks import SendViolation
from backend.commands.health import LinkHealth, link_health_of
from backend.commands.link_ber import BerChoice, CopiesFrom
from backend.commands.link_settings import ber_now, change_link
from backend.commands.manager import CommandManager
from backend.commands.service import Assessment, CommandService
from backend.control.identity import recovered_by
from backend.control.runtime import ControlRuntime, start_control
from backend.dives import Dives
from backend.messages import ActivePath, ActivePathMessage, EventMessage, LinkMessage, VehicleView
from backend.mission_log.opening import open_checked
from backend.mission_log.records import log_event
from backend.mission_log.store import MissionLog
from backend.relay.runtime import RelayRuntime
from backend.scripts.guard import RunGuard
from backend.settings import Settings
from backend.telemetry import TelemetryHub
from backend.vehicle_link import link_delay_s, open_vehicle_link
from backend.viewer.draw_queue import PreviewDrawer
from codec import Encoded, airtime_s
from planner import Limits, Plan, VehicleState
from station.link import Link, RosbridgeLink
from vehicle_contract.messages import pose_from_message

if TYPE_CHECKING:  # the heavy ones, imported when training or the 3D view starts
    from backend.foxglove_live.server import FoxgloveLive
    from backend.scripts.operations import ScriptRunner
    from backend.viewer.viewer import Viewer
    from rosbridge.server import BridgeServer
    from sim.simulation import Simulation

logger = logging.getLogger("backend.console")

#: Shortest time between two preview drawings in the 3D view (s).
PREVIEW_DRAW_INTERVAL_S = 0.1
#: How often the link's health is pushed to the page (s).
HEALTH_PUSH_INTERVAL_S = 1.0
#: Scenario presets offered in training mode.
SCENARIO_PRESETS = ("wreck", "panel", "pod", "tank")


class Console:
    """The running console (one per app)."""

    def __init__(
        self, settings: Settings, *, link: Link | None = None, clock: Clock = SYSTEM_CLOCK
    ) -> None:
        """``link``: the link to use instead of the one the settings name (no simulator
        either), e.g. a test's in-memory vehicle; ``clock``: the command delivery's."""
        self.settings = settings
        self._given_link = link
        self.clock = clock
        self.limits = Limits(max_depth_m=settings.max_depth_m, max_speed_mps=settings.max_speed_mps)
        #: The NED origin's latitude and longitude (None: not known, positions in metres only).
        self.datum: Datum | None = initial_datum(settings)
        #: The vehicle's own datum (the contract's datum topic) and its mismatch with ours.
        self.datum_watch = DatumWatch()
        #: The process /api/predict's twins run in (started on first use).
        self.twin_worker = TwinWorker()
        #: The path the vehicle flies, as mirrored (NED and lat/lon), or None.
        self.active_path: ActivePath | None = None
        #: What the vehicle can do (the twin's figures in training, the settings' otherwise).
        self.profile: VehicleProfile = profile_for(settings)
        self.gps: GpsReader | None = None  # the surface GPS (``gps`` setting)
        self.tiles: TileSource | None = None  # local map tiles (``tiles`` setting)
        self.log: MissionLog | None = None
        self.dives: Dives | None = None  # the current dive (started when the vehicle is heard)
        self.sim: Simulation | None = None  # training mode: the simulated vehicle
        self.bridge: BridgeServer | None = None  # training mode: its rosbridge server
        self.link: Link | None = None
        self.hub = TelemetryHub(settings.telemetry_hz)
        self.commands: CommandManager | None = None
        self.beliefs: Beliefs | None = None  # what each vehicle is believed to do
        #: The one checked path to the vehicle (every frame leaves through it).
        self.service: CommandService | None = None
        #: Who is in control of each vehicle; live sync with other consoles (backend.control).
        self.control: ControlRuntime | None = None
        #: Commands from a console without the transmitter, through the shared log
        #: (backend.relay): this console's sender (target relay) or outbox worker.
        self.relay: RelayRuntime | None = None
        self.viewer: Viewer | None = None  # the 3D view (None: started without one)
        #: The live Foxglove view (None: off; the app's lifespan sets it: backend.foxglove_live).
        self.foxglove: FoxgloveLive | None = None
        self.runner: ScriptRunner | None = None  # the latest mission script run (None: none yet)
        self._runner_task: asyncio.Task[None] | None = None
        self.script_commands: dict[int, int] = {}  # script step -> command id
        #: Ends the run when any other command is sent (every path: the service tells it).
        self.script_guard = RunGuard(self)
        self.drawer = PreviewDrawer(PREVIEW_DRAW_INTERVAL_S)
        self._drawer: asyncio.Task[None] | None = None
        self._health_task: asyncio.Task[None] | None = None
        #: The BER assumed of a real link (``link_ber``) and what the copies follow there.
        self.ber_choice = BerChoice(settings.link_ber)

    # --- lifecycle -----------------------------------------------------------------------

    async def start(self, *, viewer: bool = True) -> None:
        s = self.settings
        self.tiles = open_tiles(s.tiles)  # ValueError naming the setting
        gps = parse_gps(s.gps)
        if gps is not None:
            self.gps = GpsReader(gps, on_fix=self._on_fix)
            await self.gps.start()
        # checked (quick_check, not locked, writable, reachable): a LogError names the file or
        # the server and the fix
        self.log = open_checked(s.mission_log)
        # ``nemesys console`` already did this before printing its URL; an app built otherwise
        # (tests, an embedding program) gets it here, before any command is taken
        recovered = self.log.recover_interrupted(recovered_by(s))
        if recovered:
            logger.warning(
                "%d commands an earlier run left on their way are interrupted", recovered
            )
        dives = self.dives = Dives(self.log, s.target, self.hub)
        if self._given_link is not None:
            link: Link = self._given_link
        else:
            link, self.sim, self.bridge = await open_vehicle_link(s, self.limits)
        self.link = link
        link.on_pose = self._on_pose
        link.on_status = self._on_status
        link.on_datum = self._on_datum
        self.commands = CommandManager(
            self.log,
            link,
            self.hub,
            dive=dives.ensure,  # a command before the vehicle is heard starts the dive
            operator=s.operator,
            ack_timeout_s=s.ack_timeout_s,
            surface_repeat_s=s.surface_repeat_s,
            max_sends_per_minute=s.max_sends_per_minute,
            copy_interval_s=s.copy_interval_s,
            delivery_target=s.delivery_target,
            link_ber=self.link_ber,
            link_delay_s=lambda: link_delay_s(self.sim, self.bridge),
            airtime_s=airtime_s(s.bitrate_bps),
            target=s.target,
            clock=self.clock,
        )
        # who is in control, and (a shared PostgreSQL log) what the other consoles write
        self.control = start_control(self)
        self.relay = RelayRuntime(self)
        self.service = CommandService(
            self.commands, self.assess, s.operator, gate=self.control.gate, relay=self.relay.sender
        )
        self.service.watch(self.script_guard)
        self.beliefs = Beliefs(self)
        self.beliefs.start()
        link.on_mission = self._on_mission
        self.commands.vehicle.on_plan = self._show_active
        await link.start()
        if isinstance(link, RosbridgeLink) and s.training:
            await link.wait_connected(5.0)
        self.relay.start(self.service)  # the outbox taken once the link is up (training)
        self._health_task = asyncio.create_task(self._push_health(), name="link health")
        if viewer:
            from backend.viewer.viewer import Viewer

            self.viewer = Viewer(s.viewer_host, s.viewer_port)
            self._drawer = asyncio.create_task(self.drawer.run(self.viewer), name="preview drawing")

    async def stop(self) -> None:
        for task in (self._runner_task, self._drawer, self._health_task):
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
        if self.beliefs is not None:
            await self.beliefs.stop()
        if self.relay is not None:
            await self.relay.stop()
        if self.control is not None:
            await self.control.stop()
        if self.commands is not None:
            await self.commands.close()
        if self.link is not None:
            await self.link.stop()
        if self.bridge is not None:
            await self.bridge.stop()
        if self.viewer is not None:
            self.viewer.stop()
        if self.log is not None:
            self.log.close()
        if self.gps is not None:
            await self.gps.stop()
        if self.tiles is not None:
            self.tiles.close()
        self.twin_worker.close()

    def start_script_loop(self, coro: Coroutine[Any, Any, None]) -> None:
        """Run a mission script's trigger loop (replacing a finished one)."""
        if self._runner_task is not None:
            self._runner_task.cancel()
        self._runner_task = asyncio.create_task(coro, name="mission script")

    @property
    def dive(self) -> int | None:
        """The current dive's number (None: none has started since this console started)."""
        return None if self.dives is None else self.dives.current

    # --- telemetry -----------------------------------------------------------------------

    def _on_status(self, msg: dict[str, Any]) -> None:
        if self.dives is not None:
            self.dives.heard()
        self.hub.set_status(msg)
        if self.dives is not None:
            self.dives.status(self._status_of_track(msg))
        self._check_echo()

    def _on_mission(self, ack: dict[str, Any]) -> None:
        assert self.commands is not None and self.dives is not None
        self.dives.heard()
        self.commands.on_mission(ack)
        self._check_echo()

    def _check_echo(self) -> None:
        """An echo mismatch goes into the mission log, once each time it begins."""
        if self.dives is not None and self.commands is not None:
            event = self.dives.echo_mismatch(self.commands)
            if event is not None:
                self.hub.publish(EventMessage(event=log_event(event)))

    def _on_datum(self, msg: dict[str, Any]) -> None:
        """The vehicle's datum: taken when the console has none, else compared (a mismatch is
        a link health problem, and an event each time it begins)."""
        event = self.datum_watch.on_message(msg, self.datum)
        if self.datum is None and self.datum_watch.vehicle is not None:
            self.datum = self.datum_watch.vehicle
        if event is None or self.dives is None:
            return
        kind, detail, data = event
        level = logging.WARNING if kind == "datum_mismatch" else logging.INFO
        logged = self.dives.note(kind, detail, data, level=level)
        if logged is not None:
            self.hub.publish(EventMessage(event=log_event(logged)))

    def _on_fix(self, fix: GpsFix) -> None:
        if self.datum is None:  # a real vehicle without a datum setting: the first fix
            self.datum = Datum(fix.lat_deg, fix.lon_deg)

    def station(self) -> Station:
        """The ME transmitter: the GPS fix, else the station settings, else the datum."""
        s, fix = self.settings, self.gps.fix if self.gps is not None else None
        return station_of(self.datum, fix, s.station_lat_deg, s.station_lon_deg)

    def _on_pose(self, msg: dict[str, Any]) -> None:
        pose = with_lat_lon(pose_from_message(msg), self.datum)
        self.hub.set_pose(pose)
        t_s, x, y, z = pose["t_s"], pose["x_m"], pose["y_m"], pose["z_m"]
        heading, roll = pose["heading_deg"], pose["roll_deg"]
        if t_s is None or x is None or y is None or z is None or heading is None:
            return  # an unknown number: shown as unknown, counted in link health, not drawn
        if self.viewer is not None:
            self.viewer.update_pose(t_s, x, y, z, roll or 0.0, heading)
        if self.dives is not None:
            self.dives.track((t_s, x, y, z, heading), self._status_of_track(self.hub.status))

    def _status_of_track(self, status: Mapping[str, Any] | None) -> Mapping[str, Any]:
        """The status a track point keeps: ``status``, with the command the console believes
        the vehicle runs (its echo) when the vehicle does not say ``active``."""
        status = status or {}
        if "active" not in status and self.commands is not None:  # the echo instead
            status = {**status, "active": self.commands.vehicle_active}
        return status

    def _show_active(self, active: Plan | None) -> None:
        """The path the vehicle flies (as the station mirrors it): in the 3D view, and for
        every page's chart (``/api/vehicle`` and an ``active_path`` message on /ws)."""
        self.active_path = (
            None
            if active is None
            else ActivePath.model_validate(active_path_doc(active, self.datum))
        )
        self.hub.publish(ActivePathMessage(active_path=self.active_path))
        if self.viewer is None:
            return
        if active is None:
            self.viewer.clear_active()
        else:
            p = active.path
            self.viewer.show_active(p.xs, p.ys, p.zs, f"active: {active.pattern}")

    def link_ber(self) -> tuple[float, float]:
        """(bit-error rate, whole-frame loss) the copies are chosen from: the emulated
        channel's in training, else the operator's choice (:mod:`backend.commands.link_ber`)."""
        now = ber_now(self)
        return now.ber, now.loss

    def vehicle_state(self) -> VehicleState:
        """Where previews, predictions and joins start: the believed position (NED)."""
        return self.vehicle_start()[0]

    def vehicle_start(self) -> tuple[VehicleState, BelievedPosition]:
        """The believed state, and what it rests on (telemetry, dead reckoning, assumed)."""
        assert self.beliefs is not None, "the console has not started"
        return self.beliefs.default.state()

    def vehicle(self) -> VehicleView:
        """Pose, status, the vehicle's echoed active command vs the last sent, link health."""
        cm = self.commands
        return VehicleView.model_validate(
            {
                "pose": self.hub.pose,
                "status": self.hub.status,
                "active": cm.vehicle_active if cm else None,
                "last_sent": cm.last_sent if cm else None,
                "active_path": self.active_path,
                "echo_mismatch": cm.echo_mismatch if cm else False,
                "age_s": self.hub.age_s(),
                "link": self.link_health(),
                "belief": self.beliefs.default.current() if self.beliefs else None,
            }
        )

    def link_health(self) -> LinkHealth:
        """What the station knows of its link to the vehicle (not the page's websocket)."""
        assert self.link is not None and self.commands is not None
        return link_health_of(
            self.link,
            self.commands,
            self.hub,
            self.settings.target,
            ber_now(self),
            self.ber_choice.copies_from,
            datum_problem=self.datum_watch.problem(self.datum),
            mission_log=self.control.mission_log() if self.control else None,
            relay=self.relay.view() if self.relay else None,
        )

    def set_link(
        self,
        operator: str,
        link_ber: float | None,
        delivery_target: float | None,
        copies_from: CopiesFrom | None = None,
    ) -> LinkHealth:
        """Change what the station assumes of its link (:func:`backend.commands.link_settings.
        change_link`: ValueError in training for ``link_ber`` or the estimate)."""
        return change_link(self, operator, link_ber, delivery_target, copies_from)

    async def _push_health(self) -> None:
        while True:
            await asyncio.sleep(HEALTH_PUSH_INTERVAL_S)
            if self.hub.client_count:
                self.hub.publish(LinkMessage(link=self.link_health()))

    # --- authoring (backend.authoring.operations) ---------------------------------------

    def encode(self, pattern: str, params: dict[str, Any]) -> tuple[Encoded, dict[str, Any]]:
        """Encode (raises codec.EncodeError naming the field) and describe the frame."""
        return operations.encode(self, pattern, params)

    def preview(
        self, pattern: str, params: dict[str, Any], *, show: bool = True, view: str | None = None
    ) -> dict[str, Any]:
        """The frame and the path the vehicle would fly from where it is now; drawn (``show``)
        in the 3D view of page ``view`` only (None: in none).

        Raises:
            codec.EncodeError / planner.PlanError: naming the parameter at fault.
        """
        shown = show and view is not None
        return operations.preview(self, pattern, params, show=shown, view=view)[1]

    def plan_violations(self, new: Plan) -> tuple[SendViolation, ...]:
        """The send policy's checks of a planned command (a mission script's step), with the
        battery as it is now."""
        return operations.plan_violations(self, new)

    def assess(self, pattern: str, params: Mapping[str, Any]) -> Assessment:
        """The checks of a send from where the vehicle is now (the command service's).

        Raises:
            codec.EncodeError / planner.PlanError: naming the parameter at fault.
        """
        return operations.assess(self, pattern, params)

    # --- training ------------------------------------------------------------------------

    def reset_vehicle(self, start_z_m: float | None = None) -> int:
        """Training: the simulated vehicle back to its start (optionally at another depth), a
        full battery, no command; a new dive. Returns the dive."""
        if self.sim is None or self.dives is None:
            raise RuntimeError("not in training mode")
        dive = self.dives.start_new()  # first: a log that cannot be written changes nothing
        if start_z_m is None:
            self.sim.reset()
        else:
            self.sim.reset(replace(self.sim.config, start_z_m=start_z_m))
        self.hub.reset()
        if self.commands is not None:
            self.commands.reset_vehicle()
        if self.viewer is not None:
            self.viewer.reset_track()
        self._show_active(None)
        return dive
