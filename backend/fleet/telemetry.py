"""What each vehicle reports, taken in: its poses and status into its hub, the mission log's
track and the 3D view; its acknowledgements to the command manager (settled among its own
records); its echo checked; the path it flies mirrored to every page.

The single vehicle's handlers are these with the one vehicle (``nemesys``), as the console
has always taken them; a fleet's vehicle's name its track points, events and news.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from backend.chart.reach import active_path_doc, with_lat_lon
from backend.fleet.state import VehicleRuntime
from backend.messages import ActivePath, ActivePathMessage, EventMessage, for_vehicle
from backend.mission_log.records import log_event
from planner import Plan
from station.link import Link
from vehicle_contract.messages import pose_from_message

if TYPE_CHECKING:
    from backend.console import Console

__all__ = ["listen", "on_mission", "on_pose", "on_status", "show_active", "status_of_track"]


def listen(console: Console, vehicle: VehicleRuntime, link: Link) -> None:
    """Take what ``vehicle`` reports over ``link`` (the datum is the console's, whoever
    sends it)."""
    vehicle.link = link
    link.on_pose = lambda msg: on_pose(console, vehicle, msg)
    link.on_status = lambda msg: on_status(console, vehicle, msg)
    link.on_mission = lambda ack: on_mission(console, vehicle, ack)
    link.on_datum = console.on_datum


def _name(console: Console, vehicle: VehicleRuntime) -> str | None:
    """The name its track points, events and news carry (a fleet's; none: the single one)."""
    return console.fleet.news_name(vehicle)


def on_status(console: Console, vehicle: VehicleRuntime, msg: dict[str, Any]) -> None:
    if console.dives is not None:
        console.dives.heard()
    vehicle.hub.set_status(msg)
    if console.dives is not None:
        console.dives.status(status_of_track(console, vehicle, msg), _name(console, vehicle))
    check_echo(console, vehicle)


def on_mission(console: Console, vehicle: VehicleRuntime, ack: dict[str, Any]) -> None:
    assert console.commands is not None and console.dives is not None
    console.dives.heard()
    console.commands.on_mission(ack, _name(console, vehicle))
    check_echo(console, vehicle)


def check_echo(console: Console, vehicle: VehicleRuntime) -> None:
    """An echo mismatch goes into the mission log, once each time it begins."""
    if console.dives is not None and console.commands is not None:
        event = console.dives.echo_mismatch(console.commands, _name(console, vehicle))
        if event is not None:
            console.hub.publish(EventMessage(event=log_event(event)))


def on_pose(console: Console, vehicle: VehicleRuntime, msg: dict[str, Any]) -> None:
    pose = with_lat_lon(pose_from_message(msg), console.datum)
    vehicle.hub.set_pose(pose)
    t_s, x, y, z = pose["t_s"], pose["x_m"], pose["y_m"], pose["z_m"]
    heading, roll = pose["heading_deg"], pose["roll_deg"]
    if t_s is None or x is None or y is None or z is None or heading is None:
        return  # an unknown number: shown as unknown, counted in link health, not drawn
    if console.viewer is not None and vehicle.drawn:
        console.viewer.update_pose(t_s, x, y, z, roll or 0.0, heading)
    if console.dives is not None:
        track = status_of_track(console, vehicle, vehicle.hub.status)
        console.dives.track((t_s, x, y, z, heading), track, _name(console, vehicle))


def status_of_track(
    console: Console, vehicle: VehicleRuntime, status: Mapping[str, Any] | None
) -> Mapping[str, Any]:
    """The status a track point keeps: ``status``, with the command the console believes
    the vehicle runs (its echo) when the vehicle does not say ``active``."""
    status = status or {}
    cm = console.commands
    if "active" not in status and cm is not None:  # the echo instead
        mirror = cm.vehicles[vehicle.name].mirror if console.fleet.configured else cm.vehicle
        status = {**status, "active": mirror.active}
    return status


def show_active(console: Console, vehicle: VehicleRuntime, active: Plan | None) -> None:
    """The path ``vehicle`` flies (as the station mirrors it): in the 3D view (its one
    vehicle's), and for every page's chart (``/api/vehicle(s)`` and an ``active_path``
    message on /ws)."""
    path = (
        None
        if active is None
        else ActivePath.model_validate(active_path_doc(active, console.datum))
    )
    vehicle.active_path = path
    if vehicle is console.fleet.first:
        console.active_path = path
    message = ActivePathMessage(active_path=path)
    console.hub.publish(for_vehicle(message, _name(console, vehicle)))
    if console.viewer is None or not vehicle.drawn:
        return
    if active is None:
        console.viewer.clear_active()
    else:
        p = active.path
        console.viewer.show_active(p.xs, p.ys, p.zs, f"active: {active.pattern}")
