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
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
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
from pydantic import BaseModel

from backend.belief.model import Belief
from backend.chart.gps import Station
from backend.commands.lifecycle import State
from backend.dives import TRACK_INTERVAL_S
from backend.foxglove_live import scene
from backend.foxglove_live.channels import (
    ACTIVE,
    BELIEF,
    BELIEF_SCENE,
    COMMANDS,
    LINK,
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

#: The track keeps at most this many poses: past it, every other one goes and the interval
#: between poses doubles (the whole dive stays, in constant memory).
MAX_TRACK_POSES: Final = 3600
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


class Trail:
    """The dive's track: a pose at most every ``interval_s`` of the vehicle's clock, at most
    :data:`MAX_TRACK_POSES` of them (then thinned, the interval doubled)."""

    def __init__(self, interval_s: float = TRACK_INTERVAL_S) -> None:
        self.start_interval_s = interval_s
        self.interval_s = interval_s
        self.poses: list[tuple[float, Pose]] = []  # (vehicle t_s, pose)

    def clear(self) -> None:
        self.poses.clear()
        self.interval_s = self.start_interval_s

    def add(self, t_s: float, pose: Pose) -> bool:
        """Keep the pose if it is due; True when kept."""
        if self.poses and self.poses[-1][0] <= t_s < self.poses[-1][0] + self.interval_s:
            return False
        self.poses.append((t_s, pose))
        if len(self.poses) > MAX_TRACK_POSES:
            self.poses = self.poses[::2]
            self.interval_s *= 2.0
        return True


class Publisher:
    """The live view's messages from the news, on ``channels``. ``tick`` tells Foxglove the
    time (the server's broadcast time), ``new_session`` makes its clients start again (a new
    dive), ``monotonic`` is the station's clock (s)."""

    def __init__(
        self,
        channels: Channels,
        clock: DiveClock,
        *,
        tick: Callable[[int], None],
        new_session: Callable[[], None],
        monotonic: Callable[[], float],
    ) -> None:
        self.ch = channels
        self.clock = clock
        self._tick = tick
        self._new_session = new_session
        self._monotonic = monotonic
        self.trail = Trail()
        self._track_sent_s: float | None = None
        self._pose_t_s: float | None = None
        self._status: BaseModel | None = None
        self._station: tuple[float | None, ...] | None = None
        self._belief_drawn = False  # the believed position is drawn (not the fresh fix)
        #: What a late subscriber gets sent again, by topic.
        self.latched: dict[str, Callable[[], object]] = {TRACK.topic: self.send_track}

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
            words = f"command {record.id} {record.pattern}: {record.state}"
            if record.reason:
                words += f" ({record.reason})"
            level = LogLevel.Warning if record.state in TROUBLE else LogLevel.Info
            self.line(ns, level, words, "commands")
        elif isinstance(item, ActivePathMessage):
            self.active(item.active_path)
        elif isinstance(item, LinkMessage):
            ns = self.clock.now()
            self.ch.json[LINK.topic].log(message_json(item.link).encode(), log_time=ns)
            self._tick(ns)
        elif isinstance(item, EventMessage):
            event = item.event
            self.line(self.clock.now(), LogLevel.Info, f"{event.kind}: {event.detail}", "events")
        elif isinstance(item, BeliefMessage):
            self.belief(item.belief)

    def telemetry(self, item: TelemetryMessage) -> None:
        if self.clock.follow(item.dive):
            self.new_dive(item.dive)
        pose, status = item.pose, item.status
        if status is not None and status != self._status:
            self._status = status
            if self.ch.json[STATUS.topic].has_sinks():
                ns = self.clock.now() if status.t_s is None else self.clock.at(status.t_s)
                self.ch.json[STATUS.topic].log(message_json(status).encode(), log_time=ns)
        if pose is None or pose.t_s is None or pose.t_s == self._pose_t_s:
            return
        x, y, z, heading = pose.x_m, pose.y_m, pose.z_m, pose.heading_deg
        if x is None or y is None or z is None or heading is None:
            return  # an unknown number: not drawn (the page shows it unknown)
        self._pose_t_s = pose.t_s
        ns = self.clock.heard(pose.t_s)
        self._tick(ns)
        placed = Pose(position=vector(x, y, z), orientation=attitude(heading, pose.roll_deg or 0.0))
        if self.ch.pose.has_sinks():
            self.ch.pose.log(
                PoseInFrame(timestamp=stamp(ns), frame_id=FRAME, pose=placed), log_time=ns
            )
        if pose.lat_deg is not None and pose.lon_deg is not None and self.ch.fix.has_sinks():
            fix = LocationFix(
                timestamp=stamp(ns),
                frame_id=FRAME,
                latitude=pose.lat_deg,
                longitude=pose.lon_deg,
                altitude=-z,
                heading=heading_rad(heading),
            )
            self.ch.fix.log(fix, log_time=ns)
        if self.trail.add(pose.t_s, placed):
            mono = self._monotonic()
            due = self._track_sent_s is None or mono - self._track_sent_s >= TRACK_SEND_S
            if due and self.send_track():
                self._track_sent_s = mono

    def new_dive(self, dive: int | None) -> None:
        """A new dive: Foxglove's clients start again, the track is emptied, what stays drawn
        is sent again on the new dive's clock."""
        self.trail.clear()
        self._pose_t_s = self._track_sent_s = None
        self._new_session()
        if dive is not None:
            self.line(0, LogLevel.Info, f"dive {dive}: its clock starts at 0", "dives")
        for topic, send in self.latched.items():
            if topic != TRACK.topic:
                send()

    def send_track(self) -> bool:
        """The track so far, to its subscribers (none: nothing is built); True when sent."""
        if not self.ch.track.has_sinks() or not self.trail.poses:
            return False
        ns = self.clock.at(self.trail.poses[-1][0])
        poses = [pose for _t, pose in self.trail.poses]
        self.ch.track.log(
            PosesInFrame(timestamp=stamp(ns), frame_id=FRAME, poses=poses), log_time=ns
        )
        return True

    def belief(self, belief: Belief) -> None:
        p, ns = belief.position, self.clock.now()
        self.ch.json[BELIEF.topic].log(message_json(belief).encode(), log_time=ns)
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
            self.ch.belief_fix.log(fix, log_time=ns)
        if p.source == "telemetry":  # the fresh fix is the pose itself: no ring
            if self._belief_drawn:
                self._belief_drawn = False
                self.latch(BELIEF_SCENE.topic, scene.deletion)
            return
        self._belief_drawn = True
        spread = "" if p.sigma_m is None else f", +-{p.sigma_m:.1f} m"
        label = f"believed ({p.source.replace('_', ' ')}{spread})"
        self.latch(
            BELIEF_SCENE.topic,
            lambda ns: scene.belief_update("believed", ns, p.x_m, p.y_m, p.z_m, p.sigma_m, label),
        )

    # --- what the pages ask for, and the station -----------------------------------------

    def active(self, path: ActivePath | None) -> None:
        if path is None or not path.x_m:
            self.latch(ACTIVE.topic, scene.deletion)
            return
        label = f"active: {path.pattern}"
        self.latch(
            ACTIVE.topic,
            lambda ns: scene.path_update(
                "active", ns, path.x_m, path.y_m, path.z_m, label, scene.ACTIVE_RGB
            ),
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

    def latch(self, topic: str, build: Callable[[int], Any]) -> None:
        """Send ``build(now)`` on ``topic`` now, and again (built anew at its time) to a late
        subscriber and at a new dive."""
        channel = self.ch.typed[topic]

        def send() -> None:
            ns = self.clock.now()
            channel.log(build(ns), log_time=ns)

        self.latched[topic] = send
        send()

    def line(self, ns: int, level: LogLevel, words: str, name: str) -> None:
        """A log line on the ``/log`` channel."""
        self.ch.log.log(
            Log(timestamp=stamp(ns), level=level, message=words, name=name), log_time=ns
        )


__all__ = ["MAX_TRACK_POSES", "Publisher", "Trail", "level_of"]
