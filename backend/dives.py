"""The current dive: when one starts, and what the console records into it.

A dive starts at the first of:

- the vehicle heard (its first pose, status or acknowledgement since this console started);
- the training vehicle reset (always a new dive, even if one is open);
- the first record the console writes before the vehicle is heard: a command (on a one-way
  modem the vehicle may never be heard, and every command still belongs to a dive) or an
  event (a datum set from the chart; a change of control, e.g. a console on a log shared by
  consoles taking control of its vehicle at start).

A console that starts and stops with none of these adds no dive (it used to add one at every
start). The dive's start on the vehicle's clock is its first track point (the first pose
heard in it): the plots' and the replay's zero.

A fleet (``NEMESYS_VEHICLES``) dives together: one dive, its first vehicle heard starting it;
each vehicle's track points are kept at the interval of its own clock and name it, as do its
events.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

from backend.commands.manager import CommandManager
from backend.mission_log.store import LogWriteError, MissionLog
from backend.telemetry import TelemetryHub
from vehicle_contract.messages import number

logger = logging.getLogger("backend.console")

#: The track is kept at this interval of the vehicle's clock (s).
TRACK_INTERVAL_S = 1.0


class Dives:
    """The console's current dive in the mission log ``log`` (None until one starts), named
    in ``hub``'s telemetry (every page's plots follow it)."""

    def __init__(
        self,
        log: MissionLog,
        target: str,
        hub: TelemetryHub | None = None,
        vehicle_hubs: list[TelemetryHub] | None = None,
    ) -> None:
        """``vehicle_hubs``: a fleet's vehicles' hubs (their telemetry names the dive too)."""
        self.log = log
        self.target = target
        self.hub = hub
        self.vehicle_hubs = vehicle_hubs or []
        #: The current dive's number (None: none started since this console started).
        self.current: int | None = None
        #: The last kept point's time on each vehicle's clock (None: the single vehicle).
        self._last_track: dict[str | None, float] = {}
        #: The dive's start on the vehicle's clock: its first track point's ``t_s`` (None:
        #: none yet), the zero of the dive's clock.
        self.start_t_s: float | None = None
        #: An echo mismatch is logged once each time it begins (per vehicle).
        self._echo_flagged: dict[str | None, bool] = {}

    def ensure(self) -> int:
        """The current dive, started now if there is none.

        Raises:
            LogWriteError: the new dive cannot be written (nothing changed).
        """
        if self.current is None:
            self.current = self.log.new_dive(self.target)
            self._last_track.clear()
            self.start_t_s = None
            logger.info("dive %d started", self.current)
            self._started()
        return self.current

    def start_new(self) -> int:
        """A new dive even if one is open (the training vehicle was reset).

        Raises:
            LogWriteError: the new dive cannot be written (the current one stays).
        """
        self.current = self.log.new_dive(self.target)
        self._last_track.clear()
        self.start_t_s = None
        logger.info("dive %d started (vehicle reset)", self.current)
        self._started()
        return self.current

    def follow(self, dive: int) -> None:
        """Another console's dive becomes this one's current dive, nothing written: a console
        without a transmitter follows the dive the console that hears the vehicle records its
        track into (:mod:`backend.relay.telemetry`)."""
        self.current = dive
        self._last_track.clear()
        self.start_t_s = None
        logger.info("dive %d followed (another console records the vehicle into it)", dive)
        self._started()

    def _started(self) -> None:
        for hub in [*([] if self.hub is None else [self.hub]), *self.vehicle_hubs]:
            hub.dive = self.current

    def heard(self) -> int | None:
        """The vehicle was heard: the current dive (started now if none); None when the log
        cannot be written (logged: the telemetry path goes on)."""
        try:
            return self.ensure()
        except LogWriteError as err:
            logger.error("could not start a dive in the mission log: %s", err)
            return None

    def track(
        self,
        position: tuple[float, float, float, float, float],
        status: Mapping[str, Any],
        vehicle: str | None = None,
    ) -> None:
        """A pose heard (of a fleet's ``vehicle``), ``(t_s, x_m, y_m, z_m, heading_deg)``,
        with the status then: kept as a track point at most every :data:`TRACK_INTERVAL_S` of
        the vehicle's clock (a clock that went back, a vehicle restarted, starts the count
        again)."""
        dive = self.heard()
        if dive is None:
            return
        if self._due(position[0], vehicle):
            self.log.add_track(dive, *position, status=status, vehicle=vehicle)

    def status(self, status: Mapping[str, Any], vehicle: str | None = None) -> None:
        """A status heard (of a fleet's ``vehicle``): a track point without a position when
        it says the navigation is not valid (no pose comes then), at most every
        :data:`TRACK_INTERVAL_S` as the poses'."""
        t_s = number(status.get("t_s"))
        if status.get("nav_valid") is not False or t_s is None:
            return
        dive = self.heard()
        if dive is not None and self._due(t_s, vehicle):
            self.log.add_status_point(dive, t_s, status, vehicle)

    def _due(self, t_s: float, vehicle: str | None = None) -> bool:
        """Whether a point at ``t_s`` is kept (one :data:`TRACK_INTERVAL_S` after the last
        of its vehicle; a clock that went back, a vehicle restarted, starts the count
        again)."""
        last = self._last_track.get(vehicle)
        if last is not None and last <= t_s < last + TRACK_INTERVAL_S:
            return False
        self._last_track[vehicle] = t_s
        if self.start_t_s is None:
            self.start_t_s = t_s
        return True

    def event(
        self,
        kind: str,
        detail: str,
        data: Mapping[str, Any] | None = None,
        vehicle: str | None = None,
    ) -> dict[str, Any]:
        """Write an event (of a fleet's ``vehicle``) into the current dive (started now if
        none); returns it.

        Raises:
            LogWriteError: it cannot be written.
        """
        return self.log.add_event(self.ensure(), kind, detail, data, vehicle)

    def note(
        self,
        kind: str,
        detail: str,
        data: Mapping[str, Any],
        *,
        level: int = logging.INFO,
        vehicle: str | None = None,
    ) -> dict[str, Any] | None:
        """:meth:`event`, said in the console's log at ``level``; a log that cannot be written
        is said as an error instead (None: nothing was written)."""
        try:
            event = self.event(kind, detail, data, vehicle)
        except LogWriteError as err:
            logger.error("could not log %s: %s", kind, err)
            return None
        logger.log(level, "%s", detail)
        return event

    def echo_mismatch(
        self, commands: CommandManager, vehicle: str | None = None
    ) -> dict[str, Any] | None:
        """Vehicle activity this console did not cause (an echo mismatch of the single
        vehicle, or a fleet's ``vehicle``): written as an event once each time it begins;
        returns the event when one was written."""
        mirror = commands.vehicle if vehicle is None else commands.vehicles[vehicle].mirror
        mismatch = mirror.echo_mismatch
        if not mismatch or self._echo_flagged.get(vehicle, False):
            self._echo_flagged[vehicle] = mismatch
            return None
        self._echo_flagged[vehicle] = True
        detail, data = mirror.mismatch_event()
        try:
            event = self.event("echo_mismatch", detail, data, vehicle)
        except LogWriteError as err:
            logger.error("could not log an echo mismatch: %s", err)
            return None
        logger.warning("echo mismatch: %s", detail)
        return event
