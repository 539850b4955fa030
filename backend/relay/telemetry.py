"""What a console without a transmitter (``NEMESYS_TARGET=relay``: the shore) shows of the
vehicle: the track points the console that hears it (the ship) writes into the shared log.

The shore hears nothing of the vehicle itself. The ship keeps a track point a second, each
with the vehicle's status then and stamped ``at`` on its arrival (:mod:`backend.dives`,
:mod:`backend.mission_log.track`), and commits them in batches within half a second;
migration 0010 tells every other console of a batch, naming its dive. :class:`RelayedTelemetry`
then reads the dive's newest point (:meth:`backend.mission_log.store.MissionLog.
newest_track_point`) and hands it to this console's hub as the pose and status
(:meth:`backend.telemetry.TelemetryHub.set_relayed`): the page's chart, 3D view, plots,
vehicle panel and the belief show it as they show a vehicle heard directly, with these
differences, said and never hidden:

* its age is the point's true age: the database's clock now less the ship's arrival stamp
  (the ship's and the database's clocks are taken to agree: NTP, or one machine), and from
  then on it grows on this console's clock; when the ship stops writing, the age grows and
  the usual staleness rules apply (``no telemetry for N s``, amber then red);
* every telemetry names the console it came through (``relayed_via``) and the link's health
  says so (``link.relay.telemetry_via``; the page: "telemetry via ship's log, N s old");
* at most a point a second (the track's interval), and of the status only what the track
  keeps (depth, heading, speed, battery, mode, the active command, the navigation's
  validity and age); a point without a position (navigation not valid) changes the status
  only, as on the ship.

Read when a batch is told, once at start (the newest dive's newest point: a shore started
mid-mission shows where the vehicle last was, with its age) and when the database is back.
The dive the points are in becomes this console's current dive (:meth:`backend.dives.Dives.
follow`): its pages' plots follow it, and what this console records (a change of control)
goes into it. The ship's datum (in its beat: :mod:`backend.relay.ship`) is taken when this
console has none, so that the positions have a latitude and longitude.

With a fleet (``NEMESYS_VEHICLES``, the ship's fleet) each vehicle is read apart: the newest
point of the batch's dive that names it (track rows carry ``vehicle``: migration 0009), fed
to that vehicle's hub, labelled relayed as the single vehicle's; a vehicle the ship writes no
point of stays unheard (its link says why: :class:`backend.relay.link.RelayVehicleLink`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from datetime import datetime
from typing import TYPE_CHECKING, Any

from backend.chart.geo import Datum
from backend.chart.reach import with_lat_lon
from backend.fleet.state import VehicleRuntime
from backend.mission_log.store import LogWriteError
from backend.relay.model import RelayView
from vehicle_contract.messages import STATUS_NUMBERS

if TYPE_CHECKING:
    from backend.console import Console

logger = logging.getLogger("backend.relay")

#: The status keys a track point keeps besides the numbers, taken when it says them.
STATUS_EXTRAS = ("mode", "active", "nav_valid", "nav_age_s")


class RelayedTelemetry:
    """The vehicle (a fleet's: each vehicle) as console ``rt`` (a relay) reads it from the
    shared log (the module's doc); ``view``: the relay as last read (the transmitting
    console's name and datum)."""

    def __init__(self, rt: Console, view: Callable[[str | None], RelayView]) -> None:
        self._rt = rt
        self._view = view
        #: The console the last point came through (None: none read yet).
        self.via: str | None = None
        #: The console each vehicle's last point came through (None: the single vehicle).
        self._via: dict[str | None, str] = {}
        #: The newest dive followed (None: none yet).
        self._followed: int | None = None
        #: The last point fed, by vehicle (None: the single vehicle): (dive, its arrival
        #: stamp, its time on the vehicle's clock).
        self._last: dict[str | None, tuple[int, str, float]] = {}
        #: Points fed to the hubs (for the tests).
        self.fed = 0

    def notice(self, dive: int | None, by: str | None) -> None:
        """Track points of ``dive`` were committed by console ``by`` (None, None: read the
        newest dive's again): feed each vehicle's newest point if it is newer than the last
        fed. A log that cannot be read is said and left (the next batch, or the database
        back, reads again)."""
        rt = self._rt
        if rt.log is None:
            return
        fleet = rt.fleet
        for vehicle in fleet.vehicles.values():
            name = fleet.news_name(vehicle)  # None: the single vehicle, any point
            try:
                row, now_s = rt.log.newest_track_point(dive, vehicle=name)
            except LogWriteError as err:
                logger.warning("the relayed track not read: %s", err)
                return
            if row is None:
                continue
            key = (int(row["dive"]), str(row["at"]), float(row["t_s"]))
            last = self._last.get(name)
            if last is not None and key[0] == last[0] and key[1:] <= last[1:]:
                continue
            view = self._view(name)
            self.via = by or self._via.get(name) or view.via or "another console"
            self._via[name] = self.via
            self._follow(key[0], view)
            self._last[name] = key
            age_s = max(0.0, now_s - datetime.fromisoformat(key[1]).timestamp())
            self._feed(row, age_s, vehicle)

    def via_of(self, vehicle: str | None) -> str | None:
        """The console vehicle ``vehicle``'s last point came through (None: the single
        vehicle's, or the last point's of any)."""
        return self._via.get(vehicle, self.via)

    def _follow(self, dive: int, view: RelayView) -> None:
        """The ship's dive becomes this console's when it is newer (a new one: the hubs and
        3D view start again; two ships each write their own dive, and the points of the
        older still show, without going back to it); its datum is taken when this console
        has none."""
        rt = self._rt
        if rt.datum is None and view.datum_lat_deg is not None and view.datum_lon_deg is not None:
            rt.datum = Datum(view.datum_lat_deg, view.datum_lon_deg)
            logger.info("the datum of console %r taken: %s", view.via, rt.datum)
        if rt.dives is None or rt.dives.current == dive:
            return
        if self._followed is not None and dive < self._followed:
            return
        self._followed = dive
        rt.dives.follow(dive)
        rt.hub.reset()
        for vehicle in rt.fleet.vehicles.values():
            if vehicle.hub is not rt.hub:
                vehicle.hub.reset()
        if rt.viewer is not None:
            rt.viewer.reset_track()
        logger.info("following dive %d, as console %r writes it", dive, self.via)

    def _feed(self, row: dict[str, Any], age_s: float, vehicle: VehicleRuntime) -> None:
        rt = self._rt
        status: dict[str, Any] = {key: row[key] for key in STATUS_NUMBERS}
        status.update({k: row[k] for k in STATUS_EXTRAS if row[k] is not None})
        pose = None
        x, y, z, heading = row["x_m"], row["y_m"], row["z_m"], row["heading_deg"]
        if x is not None:
            pose = with_lat_lon(
                {"t_s": row["t_s"], "x_m": x, "y_m": y, "z_m": z, "heading_deg": heading},
                rt.datum,
            )
            pose["roll_deg"] = None  # not in the track
        assert self.via is not None
        vehicle.hub.set_relayed(pose, status, age_s, self.via)
        self.fed += 1
        drawn = rt.viewer is not None and vehicle.drawn and pose is not None
        if drawn and rt.viewer is not None and None not in (y, z, heading):
            rt.viewer.update_pose(row["t_s"], x, y, z, 0.0, heading)
