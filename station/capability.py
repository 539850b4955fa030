"""What a vehicle can report back over its link (:class:`Capability`), and the one rule that
decides it from the vehicle's ROS graph (:func:`capability_of`, over
:func:`station.vehicle_graph.verdict_of`, shared with ``vehicle-check``)."""

from __future__ import annotations

from enum import StrEnum

from station.vehicle_graph import VehicleGraph, verdict_of


class Capability(StrEnum):
    """What a vehicle can report back over its link."""

    #: The vehicle runs the onboard agent: acknowledgements and telemetry.
    ACKS_AND_TELEMETRY = "acks_and_telemetry"
    #: A ROS 2 vehicle without the agent: pose / status, no acknowledgements.
    TELEMETRY_ONLY = "telemetry_only"
    #: An ME modem: nothing comes back.
    NONE = "none"
    #: Not known yet (not connected, or the vehicle could not be asked).
    UNKNOWN = "unknown"

    @property
    def acknowledges(self) -> bool:
        return self is Capability.ACKS_AND_TELEMETRY

    @property
    def telemetry(self) -> bool:
        return self in (Capability.ACKS_AND_TELEMETRY, Capability.TELEMETRY_ONLY)


def capability_of(
    graph: VehicleGraph, *, frames_over_rosbridge: bool = True
) -> tuple[Capability, list[str]]:
    """What a vehicle with this ROS graph can report back, by the one rule
    (:func:`station.vehicle_graph.verdict_of`: rosbridge's own node is not the vehicle), and
    a named problem for every contract topic that is missing, of the wrong type, or only
    rosbridge's. ``frames_over_rosbridge`` False: frames go out another way (an ME modem)."""
    verdict = verdict_of(graph, frames_over_rosbridge=frames_over_rosbridge)
    problems = list(verdict.problems)
    if verdict.agent and (verdict.frames or not frames_over_rosbridge):
        return Capability.ACKS_AND_TELEMETRY, problems
    if verdict.pose or verdict.status:
        return Capability.TELEMETRY_ONLY, problems
    return Capability.NONE, problems
