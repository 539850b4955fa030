"""The page's news as Foxglove messages: every ``/ws`` message the hub sends a page
(:mod:`backend.messages`) becomes the live view's messages on its channels
(:mod:`backend.foxglove_live.channels`), on the dive's clock
(:mod:`backend.foxglove_live.clock`), in the scene frame (:mod:`backend.foxglove_live.frames`).

One truth: the view shows what the pages are told, converted, never worked out again. The
previews and predictions the pages ask for, and the ME transmitter (not news: each page asks
for its own), come in through :meth:`Publisher.path` and :meth:`Publisher.station`.

Foxglove's WebSocket protocol keeps no message for a client that subscribes later, so what
is drawn once and stays (the paths, the believed position's ring, the transmitter, the track)
is *latched*: sent again to whoever subscribes to it, and again when a new dive starts.
Single-threaded: everything here runs on the console's event loop.

With a fleet every vehicle is drawn: the news about one vehicle, named in it, goes to that
vehicle's own channels, entities and frame (:mod:`backend.foxglove_live.vehicles`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from typing import Any, Final

from foxglove.messages import (
    LocationFix,
    LocationFixPositionCovarianceType,
    Log,
    LogLevel,
    Pose,
    PoseInFrame,
    PosesInFrame,
)

from backend.belief.model import Belief
from backend.chart.gps import Station
from backend.commands.lifecycle import State
from backend.foxglove_live import scene
from backend.foxglove_live.channels import (
    ACTIVE,
    BELIEF,
    BELIEF_FIX,
    BELIEF_SCENE,
    COMMANDS,
    FIX,
    FRAMES,
    LINK,
    POSE,
    PREDICTION,
    PREVIEW,
    STATION,
    STATION_FIX,
    STATUS,
    TRACK,
    Channels,
)
from backend.foxglove_live.clock import DiveClock
from backend.foxglove_live.frames import FRAME, attitude, heading_rad, stamp, vector
from backend.foxglove_live.vehicles import (
    MAX_TRACK_POSES,
    Trail,
    ViewedVehicle,
    belief_label,
    frame_of,
)
from backend.messages import (
    ActivePath,
    ActivePathMessage,
    BeliefMessage,
    CommandMessage,
    EventMessage,
    FleetTelemetryMessage,
    LinkMessage,
    News,
    TelemetryMessage,
    message_json,
)

#: The track is sent at most this often (station s): it grows a pose at a time.
TRACK_SEND_S: Final = 1.0
#: Python's logging levels as Foxglove's.
LEVELS: Final = (
    (logging.CRITICAL, LogLevel.Fatal),
    (logging.ERROR, LogLevel.Error),
    (logging.WARNING, LogLevel.Warning),
    (logging.INFO, LogLevel.Info),
    (logging.DEBUG, LogLevel.Debug),
)
#: Command states said at a warning's level in the log lines.
TROUBLE: Final = frozenset({State.REJECTED, State.TIMED_OUT, State.FAILED, State.INTERRUPTED})


def level_of(levelno: int) -> LogLevel:
    """A Python logging level as Foxglove's (the nearest at or below it)."""
    return next((level for at, level in LEVELS if levelno >= at), LogLevel.Unknown)


class Publisher:
    """The live view's messages from the news, on ``channels``. ``tick`` tells Foxglove the
    time (the server's broadcast time), ``new_session`` makes its clients start again (a new
    dive), ``monotonic`` is the station's clock (s). ``vehicles``: a fleet's names and
    addresses, in order (empty: the single vehicle)."""

    def __init__(
        self,
        channels: Channels,
        clock: DiveClock,
        *,
        tick: Callable[[int], None],
        new_session: Callable[[], None],
        monotonic: Callable[[], float],
        vehicles: Mapping[str, int | None] | None = None,
    ) -> None:
        self.ch = channels
        self.clock = clock
        self._tick = tick
        self._new_session = new_session
        self._monotonic = monotonic
        self.fleet = bool(vehicles)
        named = [ViewedVehicle(n, a) for n, a in (vehicles or {}).items()]
        #: Each vehicle by the name its news carry (None: the single vehicle's).
        self.vehicles: dict[str | None, ViewedVehicle] = (
            {v.name: v for v in named} if named else {None: ViewedVehicle(None)}
        )
        self._station: tuple[float | None, ...] | None = None
        #: What a late subscriber gets sent again: by topic, each drawing's send by its key
        #: (a fleet's vehicle's name on a shared scene channel; "" otherwise).
        self.latched: dict[str, dict[str, Callable[[], object]]] = {}
        for v in self.vehicles.values():
            self.latched[v.topic(TRACK)] = {"": partial(self.send_track, v)}

    def _vehicle(self, name: str | None) -> ViewedVehicle | None:
        """The vehicle news naming ``name`` is about (the single one: whatever it names);
        None: not one of the fleet's."""
        return self.vehicles.get(name) if self.fleet else self.vehicles[None]

    # --- the news ------------------------------------------------------------------------

    def news(self, item: News) -> None:
        """One ``/ws`` message, as the pages get it."""
        if isinstance(item, TelemetryMessage):
            self.telemetry(item)
        elif isinstance(item, FleetTelemetryMessage):  # a fleet's: each vehicle's in turn
            for telemetry in item.telemetry:
                self.news(telemetry)
        elif isinstance(item, CommandMessage):
            record = item.command
            ns = self.clock.now()
            self.ch.json[COMMANDS.topic].log(message_json(record).encode(), log_time=ns)
            to = f" to {record.vehicle}" if record.vehicle else ""
            words = f"command {record.id} {record.pattern}{to}: {record.state}"
            if record.reason:
                words += f" ({record.reason})"
            level = LogLevel.Warning if record.state in TROUBLE else LogLevel.Info
            self.line(ns, level, words, "commands")
        elif isinstance(item, ActivePathMessage):
            self.active(item.active_path, item.vehicle)
        elif isinstance(item, LinkMessage):
            ns = self.clock.now()
            v = self._vehicle(item.vehicle)
            if v is not None:
                self.ch.json[v.topic(LINK)].log(message_json(item.link).encode(), log_time=ns)
            self._tick(ns)
        elif isinstance(item, EventMessage):
            event = item.event
            self.line(self.clock.now(), LogLevel.Info, f"{event.kind}: {event.detail}", "events")
        elif isinstance(item, BeliefMessage):
            self.belief(item.belief)

    def telemetry(self, item: TelemetryMessage) -> None:
        if self.clock.follow(item.dive):
            self.new_dive(item.dive)
        v = self._vehicle(item.vehicle)
        if v is None:
            return
        pose, status = item.pose, item.status
        status_ch = self.ch.json[v.topic(STATUS)]
        if status is not None and status != v.status:
            v.status = status
            if status_ch.has_sinks():
                ns = self.clock.now() if status.t_s is None else self.clock.at(status.t_s)
                status_ch.log(message_json(status).encode(), log_time=ns)
        if pose is None or pose.t_s is None or pose.t_s == v.pose_t_s:
            return
        x, y, z, heading = pose.x_m, pose.y_m, pose.z_m, pose.heading_deg
        if x is None or y is None or z is None or heading is None:
            return  # an unknown number: not drawn (the page shows it unknown)
        v.pose_t_s = pose.t_s
        ns = self.clock.heard(pose.t_s)
        self._tick(ns)
        roll = pose.roll_deg or 0.0
        placed = Pose(position=vector(x, y, z), orientation=attitude(heading, roll))
        pose_ch, fix_ch = self.ch.typed[v.topic(POSE)], self.ch.typed[v.topic(FIX)]
        if pose_ch.has_sinks():
            pose_ch.log(PoseInFrame(timestamp=stamp(ns), frame_id=FRAME, pose=placed), log_time=ns)
        if v.name is not None and self.ch.typed[FRAMES.topic].has_sinks():
            frame = frame_of(v.name, ns, x, y, z, heading, roll)
            self.ch.typed[FRAMES.topic].log(frame, log_time=ns)
        if pose.lat_deg is not None and pose.lon_deg is not None and fix_ch.has_sinks():
            fix = LocationFix(
                timestamp=stamp(ns),
                frame_id=FRAME,
                latitude=pose.lat_deg,
                longitude=pose.lon_deg,
                altitude=-z,
                heading=heading_rad(heading),
            )
            fix_ch.log(fix, log_time=ns)
        if v.trail.add(pose.t_s, placed):
            mono = self._monotonic()
            due = v.track_sent_s is None or mono - v.track_sent_s >= TRACK_SEND_S
            if due and self.send_track(v):
                v.track_sent_s = mono

    def new_dive(self, dive: int | None) -> None:
        """A new dive: Foxglove's clients start again, the tracks are emptied, what stays
        drawn is sent again on the new dive's clock."""
        tracks = set()
        for v in self.vehicles.values():
            v.trail.clear()
            v.pose_t_s = v.track_sent_s = None
            tracks.add(v.topic(TRACK))
        self._new_session()
        if dive is not None:
            self.line(0, LogLevel.Info, f"dive {dive}: its clock starts at 0", "dives")
        for topic in self.latched:
            if topic not in tracks:
                self.resend(topic)

    def resend(self, topic: str) -> None:
        """What stays drawn on ``topic``, sent again (a late subscriber, a new dive)."""
        for send in list(self.latched.get(topic, {}).values()):
            send()

    def send_track(self, v: ViewedVehicle | None = None) -> bool:
        """The track so far of ``v`` (None: the single vehicle, or a fleet's first), to its
        subscribers (none: nothing is built); True when sent."""
        v = v or next(iter(self.vehicles.values()))
        channel = self.ch.typed[v.topic(TRACK)]
        if not channel.has_sinks() or not v.trail.poses:
            return False
        ns = self.clock.at(v.trail.poses[-1][0])
        poses = [pose for _t, pose in v.trail.poses]
        channel.log(PosesInFrame(timestamp=stamp(ns), frame_id=FRAME, poses=poses), log_time=ns)
        return True

    def belief(self, belief: Belief) -> None:
        v = self._vehicle(belief.vehicle)
        if v is None:
            return
        p, ns = belief.position, self.clock.now()
        self.ch.json[v.topic(BELIEF)].log(message_json(belief).encode(), log_time=ns)
        if p.lat_deg is not None and p.lon_deg is not None:
            sigma2 = 0.0 if p.sigma_m is None else p.sigma_m**2
            known = LocationFixPositionCovarianceType.DiagonalKnown
            fix = LocationFix(
                timestamp=stamp(self.clock.at(p.t_s)),
                frame_id=FRAME,
                latitude=p.lat_deg,
                longitude=p.lon_deg,
                altitude=-p.z_m,
                heading=heading_rad(p.heading_deg),
                position_covariance=[sigma2, 0.0, 0.0, 0.0, sigma2, 0.0, 0.0, 0.0, 0.0],
                position_covariance_type=(
                    LocationFixPositionCovarianceType.Unknown if p.sigma_m is None else known
                ),
            )
            self.ch.typed[v.topic(BELIEF_FIX)].log(fix, log_time=ns)
        entity = v.entity("believed")
        if v.name is not None:  # a fleet's: always, named, with its address and command
            label = belief_label(v.name, v.address, belief)
            sigma = None if p.source == "telemetry" else p.sigma_m
        elif p.source == "telemetry":  # the fresh fix is the pose itself: no ring
            if v.belief_drawn:
                v.belief_drawn = False
                self.latch(BELIEF_SCENE.topic, scene.deletion)
            return
        else:
            v.belief_drawn = True
            spread = "" if p.sigma_m is None else f", +-{p.sigma_m:.1f} m"
            label = f"believed ({p.source.replace('_', ' ')}{spread})"
            sigma = p.sigma_m
        self.latch(
            BELIEF_SCENE.topic,
            lambda ns: scene.belief_update(entity, ns, p.x_m, p.y_m, p.z_m, sigma, label),
            v.key,
        )

    # --- what the pages ask for, and the station -----------------------------------------

    def active(self, path: ActivePath | None, vehicle: str | None = None) -> None:
        """The path ``vehicle`` (a fleet's; None: the single one) flies, as mirrored."""
        v = self._vehicle(vehicle)
        if v is None:
            return
        entity = v.entity("active")
        if path is None or not path.x_m:
            gone = scene.deletion if v.name is None else lambda ns: scene.deletion(ns, entity)
            self.latch(ACTIVE.topic, gone, v.key)
            return
        label = f"active: {path.pattern}" if v.name is None else f"{v.name} active: {path.pattern}"
        self.latch(
            ACTIVE.topic,
            lambda ns: scene.path_update(
                entity, ns, path.x_m, path.y_m, path.z_m, label, scene.ACTIVE_RGB
            ),
            v.key,
        )

    def path(
        self,
        topic: str,
        xs: Sequence[float],
        ys: Sequence[float],
        zs: Sequence[float],
        label: str,
        body_start: int = 0,
    ) -> None:
        """A preview (``PREVIEW.topic``: its join to ``body_start``, then its pattern) or a
        prediction (``PREDICTION.topic``) a page drew, NED m (no points: none)."""
        if topic == PREVIEW.topic:
            rgb, body, entity = scene.PREVIEW_JOIN_RGB, scene.PREVIEW_BODY_RGB, "preview"
        elif topic == PREDICTION.topic:
            rgb, body, entity = scene.PREDICTION_RGB, None, "prediction"
        else:
            raise ValueError(f"not a path topic: {topic!r}")
        if not xs:
            self.latch(topic, scene.deletion)
            return
        x, y, z = list(xs), list(ys), list(zs)
        self.latch(
            topic,
            lambda ns: scene.path_update(
                entity, ns, x, y, z, label, rgb, body_start=body_start, body_rgb=body
            ),
        )

    def station(self, where: Station, range_m: float) -> None:
        """The ME transmitter and its range ring, when they changed."""
        key = (where.lat_deg, where.lon_deg, where.x_m, where.y_m, range_m)
        if key == self._station:
            return
        self._station = key
        x, y, lat, lon = where.x_m, where.y_m, where.lat_deg, where.lon_deg
        if x is None or y is None:  # lat/lon only (no datum): nowhere in the scene
            self.latch(STATION.topic, scene.deletion)
        else:
            self.latch(STATION.topic, lambda ns: scene.station_update("station", ns, x, y, range_m))
        if lat is not None and lon is not None:
            self.latch(
                STATION_FIX.topic,
                lambda ns: LocationFix(
                    timestamp=stamp(ns), frame_id=FRAME, latitude=lat, longitude=lon
                ),
            )

    def latch(self, topic: str, build: Callable[[int], Any], key: str = "") -> None:
        """Send ``build(now)`` on ``topic`` now, and again (built anew at its time) to a late
        subscriber and at a new dive, in place of what ``key`` drew there before (a fleet's
        vehicle's name: each vehicle's drawing on a shared scene channel stays)."""
        channel = self.ch.typed[topic]

        def send() -> None:
            ns = self.clock.now()
            channel.log(build(ns), log_time=ns)

        self.latched.setdefault(topic, {})[key] = send
        send()

    def line(self, ns: int, level: LogLevel, words: str, name: str) -> None:
        """A log line on the ``/log`` channel."""
        self.ch.log.log(
            Log(timestamp=stamp(ns), level=level, message=words, name=name), log_time=ns
        )


__all__ = ["MAX_TRACK_POSES", "Publisher", "Trail", "ViewedVehicle", "level_of"]
