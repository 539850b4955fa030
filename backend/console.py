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
import functools
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
from backend.chart.tiles import TileSource, open_tiles
from backend.chart.vehicle_datum import DatumWatch
from backend.clock import SYSTEM_CLOCK, Clock
from backend.commands.checks import SendViolation
from backend.commands.health import LinkHealth
from backend.commands.link_ber import BerChoice, CopiesFrom
from backend.commands.link_settings import ber_now, change_link
from backend.commands.manager import CommandManager
from backend.commands.service import Assessment, CommandService, check_vehicle
from backend.control.identity import recovered_by
from backend.control.runtime import ControlRuntime, start_control
from backend.dives import Dives
from backend.fleet import telemetry, views
from backend.fleet.state import Fleet, members, vehicle_links
from backend.messages import ActivePath, EventMessage, VehicleView
from backend.mission_log.opening import open_checked
from backend.mission_log.records import log_event
from backend.mission_log.store import MissionLog
from backend.relay.runtime import RelayRuntime
from backend.scripts.guard import RunGuard
from backend.settings import Settings
from backend.telemetry import TelemetryHub
from backend.vehicle_link import link_delay_s, open_training_fleet, open_vehicle_link
from backend.viewer.draw_queue import PreviewDrawer
from codec import Encoded, airtime_s
from planner import Limits, Plan, VehicleState
from station.link import Link, RosbridgeLink
from station.link_fleet import FleetLink

if TYPE_CHECKING:  # the heavy ones, imported when training or the 3D view starts
    from backend.foxglove_live.server import FoxgloveLive
    from backend.scripts.operations import ScriptRunner
    from backend.viewer.viewer import Viewer
    from rosbridge.server import BridgeServer
    from sim.fleet import FleetSimulation
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
        #: Training mode: the simulated vehicle (a fleet's first: each is ``sim_of``'s).
        self.sim: Simulation | None = None
        self.fleet_sim: FleetSimulation | None = None  # training with a fleet: every vehicle
        self.bridge: BridgeServer | None = None  # training mode: its rosbridge server
        self.link: Link | None = None
        self.hub = TelemetryHub(settings.telemetry_hz)
        #: Every vehicle (a fleet's, or the single one): its hub, its link, its path.
        self.fleet = Fleet(settings.fleet, self.hub)
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
        fleet = self.fleet
        extra = [v.hub for v in fleet.vehicles.values() if v.hub is not self.hub]
        dives = self.dives = Dives(self.log, s.target, self.hub, extra)
        if self._given_link is not None:
            link: Link = self._given_link
        else:
            link, self.sim, self.bridge = await self._open_link()
        self.link = link
        for vehicle, its_link in vehicle_links(fleet, link):
            telemetry.listen(self, vehicle, its_link)
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
            fleet=members(fleet),
            link_ber_of=self.link_ber if fleet.configured else None,
        )
        # who is in control, and (a shared PostgreSQL log) what the other consoles write
        self.control = start_control(self)
        self.relay = RelayRuntime(self)
        self.service = CommandService(
            self.commands, self.assess, s.operator, gate=self.control.gate, relay=self.relay.sender
        )
        self.service.watch(self.script_guard)
        self.beliefs = Beliefs(self, tuple(fleet.names))
        self.beliefs.start()
        for vehicle in fleet.vehicles.values():
            mirror = self.commands.addressee(fleet.news_name(vehicle)).mirror
            mirror.on_plan = functools.partial(telemetry.show_active, self, vehicle)
        await link.start()
        if isinstance(link, RosbridgeLink | FleetLink) and s.training:
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

    async def _open_link(self) -> tuple[Link, Simulation | None, BridgeServer | None]:
        """The settings' link; in training the simulator (a fleet's: every vehicle on one
        link, :attr:`fleet_sim`) and its bridge."""
        s = self.settings
        if not (s.training and s.fleet):
            return await open_vehicle_link(s, self.limits)
        link, self.fleet_sim, bridge = await open_training_fleet(s, self.limits)
        return link, self.fleet_sim.sim(self.fleet.first.name), bridge

    def sim_of(self, vehicle: str) -> Simulation | None:
        """Training: vehicle ``vehicle``'s simulation (a fleet's own; the single one's)."""
        if self.fleet_sim is not None:
            return self.fleet_sim.sim(vehicle)
        return self.sim

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

    def on_datum(self, msg: dict[str, Any]) -> None:
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

    def link_ber(self, vehicle: str | None = None) -> tuple[float, float]:
        """(bit-error rate, whole-frame loss) the copies (to a fleet's ``vehicle``) are
        chosen from: the emulated channel's in training, else the operator's choice
        (:mod:`backend.commands.link_ber`)."""
        now = ber_now(self, vehicle)
        return now.ber, now.loss

    def vehicle_state(self, vehicle: str | None = None) -> VehicleState:
        """Where previews, predictions and joins start: the believed position (NED) of the
        vehicle (a fleet's ``vehicle``; None: the single one, or a fleet's first)."""
        return self.vehicle_start(vehicle)[0]

    def vehicle_start(self, vehicle: str | None = None) -> tuple[VehicleState, BelievedPosition]:
        """The believed state, and what it rests on (telemetry, dead reckoning, assumed).

        Raises:
            UnknownVehicle: a vehicle the console does not have, naming those it has.
        """
        assert self.beliefs is not None, "the console has not started"
        return self.beliefs[self.fleet.get(vehicle).name].state()

    def vehicle(self, name: str | None = None) -> VehicleView:
        """Pose, status, the vehicle's echoed active command vs the last sent, link health
        (of a fleet's vehicle ``name``: :mod:`backend.fleet.views`)."""
        return views.vehicle_view(self, name)

    def checked_vehicle(self, name: str | None, *, surface: bool = False) -> str | None:
        """The vehicle a request names, checked (:func:`backend.commands.service.check_vehicle`:
        a fleet's name, ``"all"`` for Surface; None without a fleet).

        Raises:
            VehicleRefused: naming the vehicles.
        """
        return check_vehicle(
            name, self.fleet.names if self.fleet.configured else [], surface=surface
        )

    def link_health(self, vehicle: str | None = None) -> LinkHealth:
        """What the station knows of its link to the vehicle (not the page's websocket)."""
        return views.link_health(self, vehicle)

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
                for news in views.link_news(self):
                    self.hub.publish(news)

    # --- authoring (backend.authoring.operations) ---------------------------------------

    def encode(self, pattern: str, params: dict[str, Any]) -> tuple[Encoded, dict[str, Any]]:
        """Encode (raises codec.EncodeError naming the field) and describe the frame."""
        return operations.encode(self, pattern, params)

    def preview(
        self,
        pattern: str,
        params: dict[str, Any],
        *,
        show: bool = True,
        view: str | None = None,
        vehicle: str | None = None,
    ) -> dict[str, Any]:
        """The frame and the path the vehicle (a fleet's ``vehicle``) would fly from where it
        is now; drawn (``show``) in the 3D view of page ``view`` only (None: in none).

        Raises:
            codec.EncodeError / planner.PlanError: naming the parameter at fault.
        """
        shown = show and view is not None
        return operations.preview(self, pattern, params, show=shown, view=view, vehicle=vehicle)[1]

    def plan_violations(self, new: Plan, vehicle: str | None = None) -> tuple[SendViolation, ...]:
        """The send policy's checks of a planned command (a mission script's step), with the
        battery (of a fleet's ``vehicle``) as it is now."""
        return operations.plan_violations(self, new, vehicle)

    def assess(
        self, pattern: str, params: Mapping[str, Any], vehicle: str | None = None
    ) -> Assessment:
        """The checks of a send from where the vehicle (a fleet's ``vehicle``) is now (the
        command service's); the frame carries its address.

        Raises:
            codec.EncodeError / planner.PlanError: naming the parameter at fault.
        """
        return operations.assess(self, pattern, params, vehicle)

    # --- training ------------------------------------------------------------------------

    def reset_vehicle(self, start_z_m: float | None = None) -> int:
        """Training: the simulated vehicle back to its start (optionally at another depth), a
        full battery, no command; a new dive. Returns the dive."""
        if self.sim is None or self.dives is None:
            raise RuntimeError("not in training mode")
        dive = self.dives.start_new()  # first: a log that cannot be written changes nothing
        fleet = self.fleet_sim
        if fleet is not None:  # every vehicle from its own start; a new first simulation
            fleet.reset(None if start_z_m is None else replace(fleet.config, start_z_m=start_z_m))
            self.sim = fleet.sim(self.fleet.first.name)
        elif start_z_m is None:
            self.sim.reset()
        else:
            self.sim.reset(replace(self.sim.config, start_z_m=start_z_m))
        for vehicle in self.fleet.vehicles.values():
            vehicle.hub.reset()
        if self.commands is not None:
            self.commands.reset_vehicle()
        if self.viewer is not None:
            self.viewer.reset_track()
        for vehicle in self.fleet.vehicles.values():
            telemetry.show_active(self, vehicle, None)
        return dive
