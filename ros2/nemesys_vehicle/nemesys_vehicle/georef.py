"""Where ``map_ned`` is on the Earth: the datum, and the odometry's origin in it.

The odometry (REP-103 ENU) has its origin wherever the navigation started; the contract's
``map_ned`` is about the datum (``/nemesys/datum``), the point the console's chart also takes
as its origin. :class:`Georef` holds the two and is the one place odometry becomes
``map_ned`` (:meth:`Georef.to_map`, through :func:`nemesys_vehicle.frames.odometry_to_map`):

* ``datum_source: parameters`` with ``odometry_origin_at_datum: true``: the datum is the
  parameters' and the navigation started there: referenced at once;
* ``datum_source: parameters`` otherwise: the datum is the parameters'; the first
  ``NavSatFix`` at the surface says where the vehicle is in ``map_ned``, which places the
  odometry's origin;
* ``datum_source: navsatfix``: the first ``NavSatFix`` at the surface is the datum (the
  vehicle is then at ``map_ned`` 0, 0), which places the odometry's origin.

Later fixes move nothing: fusing GPS into the navigation is the navigation's job, and a
``map_ned`` that jumped would move every plan flown in it. Until referenced the vehicle has no
``map_ned`` position: no pose, and nothing planned (``no_navigation``).
"""

from __future__ import annotations

from typing import Any

from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.frames import EnuPose, MapOrigin, NedPose, map_to_odometry, odometry_to_map
from nemesys_vehicle.geo import check_lat_lon, geodetic_to_ned

JsonDict = dict[str, Any]


class Georef:
    """The datum and the odometry's origin in ``map_ned`` (see the module doc)."""

    def __init__(self, config: VehicleConfig) -> None:
        self.config = config
        self.declination_deg = config.magnetic_declination_deg
        #: (lat_deg, lon_deg) of map_ned's origin, or None until known.
        self.datum: tuple[float, float] | None = None
        #: How the datum was set (the datum message's ``source``) and when (ROS time, s).
        self.source = config.datum_source
        self.set_t_s: float | None = None
        #: The odometry's origin in map_ned (None until a fix places it).
        self.origin: MapOrigin | None = None
        if config.datum_source == "parameters":
            self.datum = (config.datum_lat_deg, config.datum_lon_deg)
            if config.odometry_origin_at_datum:
                self.origin = MapOrigin(0.0, 0.0, self.declination_deg)

    @property
    def referenced(self) -> bool:
        """Whether odometry can be put in map_ned (the datum and the origin are known)."""
        return self.datum is not None and self.origin is not None

    def waiting_for(self) -> str:
        """What is missing, in words (for a ``no_navigation`` rejection)."""
        what = "the datum" if self.datum is None else "where the navigation started"
        return (
            f"navigation not geo-referenced yet: {what} comes from the first "
            f"{self.config.navsatfix_topic} fix at the surface (depth <= "
            f"{self.config.fix_max_depth_m:g} m)"
        )

    def to_map(self, enu: EnuPose) -> NedPose:
        """An odometry pose in map_ned (the one conversion; the caller checks
        :attr:`referenced`)."""
        if self.origin is None:
            raise RuntimeError("not geo-referenced yet")
        return odometry_to_map(enu, self.origin)

    def to_odometry(self, ned: NedPose) -> EnuPose:
        """A map_ned pose in the odometry's frame (setpoints for a REP-103 autopilot)."""
        if self.origin is None:
            raise RuntimeError("not geo-referenced yet")
        return map_to_odometry(ned, self.origin)

    def on_fix(self, lat_deg: float, lon_deg: float, at: EnuPose, t_s: float) -> bool:
        """A GPS fix taken with the vehicle at odometry pose ``at`` (fresh, at the surface:
        the caller checks). Places the datum and the origin when not yet known; True when it
        did (the datum message is then due at once).

        Raises:
            ValueError: a latitude or longitude out of range (naming it).
        """
        check_lat_lon(lat_deg, lon_deg)
        if self.referenced:
            return False
        if self.datum is None:
            self.datum = (lat_deg, lon_deg)
            self.source = "navsatfix"
        here_north_m, here_east_m = geodetic_to_ned(*self.datum, lat_deg, lon_deg)
        # the odometry's position turned to true north, without an origin
        turned = odometry_to_map(at, MapOrigin(0.0, 0.0, self.declination_deg))
        self.origin = MapOrigin(
            here_north_m - turned.x_north_m, here_east_m - turned.y_east_m, self.declination_deg
        )
        self.set_t_s = t_s
        return True

    def datum_msg(self, t_s: float) -> JsonDict | None:
        """The datum message (contract schema ``datum``), None while there is no datum."""
        if self.datum is None:
            return None
        if self.set_t_s is None:  # set by the parameters: from its first message on
            self.set_t_s = t_s
        origin = self.origin
        return {
            "t_s": self.set_t_s,
            "lat_deg": self.datum[0],
            "lon_deg": self.datum[1],
            "source": self.source,
            "odometry_origin": (
                None if origin is None else {"north_m": origin.north_m, "east_m": origin.east_m}
            ),
        }
