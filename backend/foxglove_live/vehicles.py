"""Each vehicle as the live view keeps it (:class:`ViewedVehicle`): its track (:class:`Trail`),
its last pose's time and status, and the names it is shown under. Without a fleet there is
one, unnamed, on the channels and entity ids the view has always used (``/vehicle/pose``,
``active``). With a fleet (``NEMESYS_VEHICLES``) each vehicle's own channels are under
``/<name>`` (:func:`backend.foxglove_live.channels.vehicle_topic`), its entities on the shared
scene channels are ``<name>/...``, its frame is ``<name>`` (:func:`frame_of`) and its believed
position is labelled with what the console's own 3D view says of it (:func:`belief_label`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Final

from foxglove.messages import FrameTransform, FrameTransforms, Pose
from pydantic import BaseModel

from backend.belief.label import fleet_label
from backend.belief.model import Belief
from backend.dives import TRACK_INTERVAL_S
from backend.foxglove_live.channels import Spec, vehicle_topic
from backend.foxglove_live.frames import FRAME, attitude, stamp, vector

#: The track keeps at most this many poses: past it, every other one goes and the interval
#: between poses doubles (the whole dive stays, in constant memory).
MAX_TRACK_POSES: Final = 3600

#: Where a believed position comes from, in the label's words (the console's 3D view's).


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


@dataclass(eq=False)
class ViewedVehicle:
    """One vehicle in the view: ``name`` None is the single vehicle (no fleet), on the
    channels and entity ids the view has always used; a fleet's are named by it."""

    name: str | None
    #: A fleet vehicle's address (1-15); None: the single vehicle.
    address: int | None = None
    trail: Trail = field(default_factory=Trail)
    #: When its track was last sent (station s; None: not yet in this dive).
    track_sent_s: float | None = None
    #: Its last pose's time (its clock, s): a pose heard again is not sent again.
    pose_t_s: float | None = None
    #: Its last status (sent on a change only).
    status: BaseModel | None = None
    #: The single vehicle's believed position is drawn (not the fresh fix).
    belief_drawn: bool = False

    def topic(self, spec: Spec) -> str:
        """Its channel of ``spec`` (a fleet's: under ``/<name>``)."""
        return vehicle_topic(spec.topic, self.name)

    def entity(self, what: str) -> str:
        """Its entity id on a shared scene channel (a fleet's: ``<name>/<what>``)."""
        return what if self.name is None else f"{self.name}/{what}"

    @property
    def key(self) -> str:
        """What its latched drawings are kept under on a shared channel ("": the single
        vehicle's, the only one)."""
        return self.name or ""


def frame_of(
    name: str, ns: int, x_m: float, y_m: float, z_m: float, heading_deg: float, roll_deg: float
) -> FrameTransforms:
    """Vehicle ``name``'s frame (child ``name`` of the scene frame) at its pose (NED m, deg):
    the 3D panel draws it as axes labelled with its name, and can follow it."""
    transform = FrameTransform(
        timestamp=stamp(ns),
        parent_frame_id=FRAME,
        child_frame_id=name,
        translation=vector(x_m, y_m, z_m),
        rotation=attitude(heading_deg, roll_deg),
    )
    return FrameTransforms(transforms=[transform])


def belief_label(name: str, address: int | None, belief: Belief) -> str:
    """The label the console's 3D view gives a fleet's vehicle
    (:func:`backend.belief.label.fleet_label`), from its belief."""
    c, p = belief.command, belief.position
    where = (p.x_m, p.y_m, p.z_m)
    return fleet_label(name, address, (c.kind, c.pattern, c.p), where, p.source, p.sigma_m)


__all__ = ["MAX_TRACK_POSES", "Trail", "ViewedVehicle", "belief_label", "frame_of"]
