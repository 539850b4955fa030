"""The belief of the running console's vehicle: its evidence read from the console (the last
fix and status in the telemetry hub, the last acknowledgement in the command manager's mirror,
the records in the mission log), the belief served on request and pushed to every page (a
``belief`` message on ``/ws``) when it changes.

A command's state change, an acknowledgement or a status pushes at once (the hub's news wakes
the tracker); a new position at most every :data:`POSITION_PUSH_S`; while the position is
dead-reckoned or assumed, at least every :data:`RECKONING_PUSH_S`. One tracker per vehicle,
keyed by its name in :class:`Beliefs`: the single vehicle's, or one per vehicle of a fleet,
each reading that vehicle's hub, mirror and records.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import threading
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Final, Protocol

from backend.authoring.profile import VehicleProfile
from backend.belief.commands import Echo
from backend.belief.estimate import Evidence, estimate
from backend.belief.label import fleet_label
from backend.belief.model import DEFAULT_VEHICLE, Belief, BelievedPosition
from backend.belief.position import Fix, Start
from backend.belief.reckoning import UNKNOWN_CURRENT, Current
from backend.chart.geo import Datum
from backend.commands.manager import CommandManager
from backend.messages import BeliefMessage, News
from backend.mission_log.store import MissionLog
from backend.settings import Settings
from backend.telemetry import TelemetryHub
from planner import VehicleState
from station.link import Link
from vehicle_contract.messages import number

if TYPE_CHECKING:
    from backend.commands.vehicles import Addressee
    from backend.fleet.state import Fleet
    from backend.viewer.viewer import Viewer
    from rosbridge.server import BridgeServer
    from sim.simulation import Simulation

__all__ = ["POSITION_PUSH_S", "RECKONING_PUSH_S", "BeliefTracker", "Beliefs", "Runtime"]

#: A new position is pushed at most this often (s); the telemetry message carries every fix.
POSITION_PUSH_S: Final = 0.5
#: A dead-reckoned or assumed position is pushed at least this often (s).
RECKONING_PUSH_S: Final = 1.0
#: The tracker looks again this often (s) when nothing wakes it.
TICK_S: Final = 0.25
#: A belief asked for within this long of the last one is that one (s).
CACHE_S: Final = 0.05
#: The records a belief reads (the newest of this vehicle's, in wire order).
RECORDS_WINDOW: Final = 50
#: News that changes the belief at once.
_WAKING: Final = frozenset({"command", "vehicle", "active_path"})


class Runtime(Protocol):
    """What the tracker reads of the running console (:class:`backend.console.Console`)."""

    settings: Settings
    log: MissionLog | None
    commands: CommandManager | None
    hub: TelemetryHub
    link: Link | None
    sim: Simulation | None
    bridge: BridgeServer | None
    datum: Datum | None
    profile: VehicleProfile
    viewer: Viewer | None
    fleet: Fleet

    @property
    def dive(self) -> int | None: ...

    def sim_of(self, vehicle: str) -> Simulation | None: ...


def _echo_of(doc: Mapping[str, Any], at_s: float, what: str) -> Echo | None:
    """The echo a status or an acknowledgement carries (None: it says nothing of it)."""
    if "active" in doc:
        return Echo(_command_of(doc["active"]), at_s, what)
    if what == "status" and "pattern" in doc:
        pattern = doc["pattern"]
        command = {"pattern": pattern, "params": None} if isinstance(pattern, str) else None
        return Echo(command, at_s, what)
    return None


def _command_of(active: object) -> Mapping[str, Any] | None:
    """An echoed command ``{pattern, params}`` (None: no command, or not one)."""
    if isinstance(active, Mapping) and isinstance(active.get("pattern"), str):
        return active
    return None


def _state_of(doc: Mapping[str, Any], speed: float | None) -> VehicleState | None:
    values = [number(doc.get(k)) for k in ("x_m", "y_m", "z_m")]
    x, y, z = values
    if x is None or y is None or z is None:
        return None
    return VehicleState(
        x,
        y,
        max(0.0, z),
        number(doc.get("heading_deg")) or 0.0,
        speed if speed is not None else number(doc.get("speed_mps")) or 0.0,
        number(doc.get("t_s")) or 0.0,
    )


class BeliefTracker:
    """One vehicle's belief, from the console ``rt`` (see the module's doc). It keeps no
    evidence of its own: the hub keeps the last fix and status, the command manager's mirror
    the last acknowledgement, the mission log the records."""

    def __init__(
        self, rt: Runtime, vehicle: str = DEFAULT_VEHICLE, now: Callable[[], float] = time.time
    ) -> None:
        self.rt = rt
        self.vehicle = vehicle
        self._now = now
        self._lock = threading.Lock()
        self._seq = 0
        self._cached: tuple[float, Belief] | None = None
        #: The records read last (the belief goes on with them while the log is unreadable).
        self._records: list[dict[str, Any]] = []
        self._pushed: Belief | None = None
        self._pushed_at = -math.inf
        self._drawn = False  # the 3D view shows a believed position
        self._wake = asyncio.Event()
        self._loop: asyncio.AbstractEventLoop | None = None  # the push loop's (run)

    # --- the evidence --------------------------------------------------------------------------

    def _hub(self) -> TelemetryHub:
        """The hub holding this vehicle's pose and status."""
        return self.rt.fleet.get(self.vehicle).hub

    def _delivery(self) -> Addressee | None:
        """What the command manager keeps of this vehicle (None: not started)."""
        cm = self.rt.commands
        if cm is None:
            return None
        return cm.addressee(self.vehicle if self.rt.fleet.configured else None)

    def _heard(self) -> tuple[Fix | None, Echo | None]:
        """The last fix (a pose, or the state an accepted acknowledgement planned from) and the
        vehicle's last word on what it runs (its status, or an acknowledgement)."""
        hub, delivery = self._hub(), self._delivery()
        now, mono = self._now(), time.monotonic()
        fixes: list[Fix] = []
        echoes: list[Echo] = []
        status = hub.status or {}
        pose = hub.known_pose
        if pose is not None and hub.known_pose_s is not None:
            state = _state_of(pose, number(status.get("speed_mps")))
            if state is not None:
                fixes.append(Fix(state, now - (mono - hub.known_pose_s), "pose"))
        if hub.status is not None and hub.status_s is not None:
            echo = _echo_of(hub.status, now - (mono - hub.status_s), "status")
            echoes += [echo] if echo is not None else []
        mirror = delivery.mirror if delivery is not None else None
        if mirror is not None and mirror.heard_s is not None:
            at = now - (mono - mirror.heard_s)
            echoes.append(Echo(_command_of(mirror.active), at, "acknowledgement"))
        if mirror is not None and mirror.planned_from is not None:
            heard_s, planned = mirror.planned_from
            state = _state_of(planned, None)
            if state is not None:
                fixes.append(Fix(state, now - (mono - heard_s), "acknowledgement"))
        fix = max(fixes, key=lambda f: (f.state.t_s, f.at_s), default=None)
        echo = max(echoes, key=lambda e: e.at_s, default=None)
        return fix, echo

    # --- the belief ----------------------------------------------------------------------------

    def evidence(self) -> Evidence:
        rt, cm, delivery = self.rt, self.rt.commands, self._delivery()
        now = self._now()
        fix, echo = self._heard()
        records: list[dict[str, Any]] = []
        if rt.log is not None and cm is not None:
            # the simulator restarts with a dive (none yet: nothing sent to this one); a real
            # vehicle runs on across dives and console restarts
            dive = rt.dive if rt.sim is not None else None
            if rt.sim is None or dive is not None:
                vehicle = self.vehicle if rt.fleet.configured else None
                # a console without a transmitter (relay): its commands are the records the
                # transmitting console made of them, under that console's target
                target = None if rt.settings.relay else cm.target
                try:
                    newest = rt.log.commands(
                        target=target, dive=dive, vehicle=vehicle, limit=RECORDS_WINDOW
                    )
                    records = self._records = newest[::-1]
                except rt.log.read_errors:  # a database out of reach: what was read last
                    records = self._records
        sim = rt.sim_of(self.vehicle) if rt.sim is not None else None  # its own twin
        if sim is not None:
            c = sim.config
            start = Start(
                VehicleState(c.start_x_m, c.start_y_m, c.start_z_m, c.start_heading_deg),
                f"the simulator's start (x {c.start_x_m:g} m, y {c.start_y_m:g} m, depth "
                f"{c.start_z_m:g} m, heading {c.start_heading_deg:g} deg)",
            )
            drift = sim.current.config
            turn_rad = math.radians(drift.direction_sigma_deg)
            sigma = math.hypot(
                drift.speed_sigma_mps, math.hypot(drift.north_mps, drift.east_mps) * turn_rad
            )
            north, east = float(sim.vehicle.current_n), float(sim.vehicle.current_e)
            current = Current(north, east, sigma, "the simulator's current")
        else:
            start = Start(
                VehicleState(0.0, 0.0, 0.0),
                "the datum's origin at the surface (x 0, y 0, depth 0): nothing is known of "
                "where the vehicle is",
            )
            current = UNKNOWN_CURRENT
        scale = rt.bridge.time_scale if rt.bridge is not None else 1.0
        return Evidence(
            vehicle=self.vehicle,
            now_s=now,
            time_scale=scale,
            two_way=delivery.acknowledges if delivery is not None else False,
            records=records,
            last_sent=delivery.last_sent if delivery is not None else None,
            accepted=delivery.mirror.accepted if delivery is not None else None,
            echo=echo,
            mirror=delivery.mirror.plan if delivery is not None else None,
            fix=fix,
            start=start,
            current=current,
            datum=rt.datum,
            top_speed_mps=rt.profile.top_speed_mps or rt.settings.max_speed_mps,
            vehicle_now_s=sim.t_s if sim is not None else None,
        )

    def current(self) -> Belief:
        """The belief now (the same one within :data:`CACHE_S`)."""
        with self._lock:
            clock = time.monotonic()
            if self._cached is not None and clock - self._cached[0] < CACHE_S:
                return self._cached[1]
            belief = estimate(self.evidence(), self._seq)
            self._cached = (clock, belief)
            return belief

    def state(self) -> tuple[VehicleState, BelievedPosition]:
        """Where previews and predictions start: the believed position, and what it rests on."""
        p = self.current().position
        return VehicleState(p.x_m, p.y_m, max(0.0, p.z_m), p.heading_deg, p.speed_mps, p.t_s), p

    # --- pushing --------------------------------------------------------------------------------

    def poke(self) -> None:
        """Something changed: look again now (from any thread: news may be published from
        the server's thread pool)."""
        self._cached = None
        loop = self._loop
        if loop is None:
            return
        try:
            here = asyncio.get_running_loop()
        except RuntimeError:
            here = None
        if here is loop:
            self._wake.set()
        else:
            loop.call_soon_threadsafe(self._wake.set)

    def on_news(self, news: News) -> None:
        """The hub's observer: a command's state, an echo or the active path changed."""
        if news.type in _WAKING:
            self.poke()

    def refresh(self) -> Belief | None:
        """Push the belief when it changed (see the module's doc); returns what was pushed.
        Nothing is worked out while no page listens and there is no 3D view."""
        if not self.rt.hub.client_count and self.rt.viewer is None:
            return None
        belief = self.current()
        old, clock = self._pushed, time.monotonic()
        since = clock - self._pushed_at
        moved = old is None or _where(old.position) != _where(belief.position)
        reckoned = belief.position.source != "telemetry"
        if not (
            old is None
            or _what(old) != _what(belief)
            or (moved and since >= POSITION_PUSH_S)
            or (reckoned and since >= RECKONING_PUSH_S)
        ):
            return None
        with self._lock:
            self._seq += 1
            belief = belief.model_copy(update={"seq": self._seq})
            self._cached = (clock, belief)
        self._pushed, self._pushed_at = belief, clock
        if self.rt.hub.client_count:
            self.rt.hub.publish(BeliefMessage(belief=belief))
        self._show(belief)
        return belief

    def _show(self, belief: Belief) -> None:
        """The 3D view: the believed position and its ring unless it is the fresh fix; a
        fleet's vehicle: its own marker and label (:mod:`backend.viewer.fleet`)."""
        viewer = self.rt.viewer
        if viewer is None:
            return
        p = belief.position
        if self.rt.fleet.configured:
            self._show_in_fleet(viewer, belief)
            return
        from backend.viewer.belief import belief_drawing, clear_belief  # viser: with the view

        if p.source == "telemetry":
            if self._drawn:
                viewer.draw_shared(clear_belief)
                self._drawn = False
            return
        spread = "" if p.sigma_m is None else f", +-{p.sigma_m:.1f} m"
        label = f"believed ({p.source.replace('_', ' ')}{spread})"
        viewer.draw_shared(belief_drawing(p.x_m, p.y_m, p.z_m, p.sigma_m, label))
        self._drawn = True

    def _show_in_fleet(self, viewer: Viewer, belief: Belief) -> None:
        """This vehicle of the fleet: where it is believed to be, named, with its address
        and the command it is believed to run."""
        from backend.viewer.fleet import fleet_drawing  # viser: with the view

        p, c = belief.position, belief.command
        address = self.rt.fleet.get(self.vehicle).address
        sigma = None if p.source == "telemetry" else p.sigma_m
        where = (p.x_m, p.y_m, p.z_m)
        label = fleet_label(self.vehicle, address, (c.kind, c.pattern, c.p), where, p.source, sigma)
        viewer.draw_shared(fleet_drawing(self.vehicle, label, *where, sigma))

    async def run(self) -> None:
        """Push on every change until cancelled."""
        self._loop = asyncio.get_running_loop()
        while True:
            # asyncio.timeout, not wait_for: on 3.11 wait_for can swallow a cancel that comes
            # as its timeout fires, and this loop would then outlive the console's stop
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(TICK_S):
                    await self._wake.wait()
            self._wake.clear()
            self.refresh()


def _what(b: Belief) -> Any:
    """What changes a belief at once: everything but the position's numbers and the ages."""
    return b.model_dump(
        exclude={"seq": True, "position": True, "surface": {"changed_s"}}
    ), b.position.source


def _where(p: BelievedPosition) -> tuple[float, ...]:
    return tuple(round(v, 2) for v in (p.x_m, p.y_m, p.z_m, p.sigma_m or 0.0))


class Beliefs:
    """The beliefs of the console's vehicles, by name (one today)."""

    def __init__(self, rt: Runtime, names: tuple[str, ...] = (DEFAULT_VEHICLE,)) -> None:
        self.trackers = {name: BeliefTracker(rt, name) for name in names}
        self._tasks: list[asyncio.Task[None]] = []
        for tracker in self.trackers.values():
            rt.hub.observers.append(tracker.on_news)

    def __getitem__(self, name: str) -> BeliefTracker:
        return self.trackers[name]

    @property
    def default(self) -> BeliefTracker:
        return next(iter(self.trackers.values()))

    def start(self) -> None:
        for name, tracker in self.trackers.items():
            self._tasks.append(asyncio.create_task(tracker.run(), name=f"belief of {name}"))

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
