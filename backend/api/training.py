"""Training controls for the simulated vehicle: channel, current, time scale, reset, presets."""

from __future__ import annotations

import math
from dataclasses import asdict, replace
from typing import TYPE_CHECKING, Any

from fastapi import APIRouter, HTTPException

from backend.api.deps import ConsoleDep, OperatorDep
from backend.api.models import ChannelIn, CurrentIn, TimeScaleIn
from backend.api.schemas import (
    OPERATOR,
    ChannelSettings,
    CurrentSettings,
    NewDive,
    ScenarioLoaded,
    TimeScale,
    TrainingOff,
    TrainingOn,
    errors,
)
from backend.api.schemas.errors import ERROR_TEXT
from backend.api.schemas.training import ChannelStats, Retask, VehicleChannelStats
from backend.commands.service import SendRequest
from backend.console import SCENARIO_PRESETS

if TYPE_CHECKING:
    from rosbridge.server import BridgeServer
    from sim.fleet import FleetSimulation
    from sim.simulation import Simulation

router = APIRouter(prefix="/api/training", tags=["training"])

#: 409 on every control: a real vehicle has none.
NO_SIM = {409: "training controls need the simulated vehicle (target 'sim')"}
#: The errors of a training control with a body.
SETTING = errors((*OPERATOR, 409, 413, 422), why=NO_SIM)


def _sim(console: ConsoleDep) -> Simulation:
    if console.sim is None:
        raise HTTPException(409, NO_SIM[409])
    return console.sim


def _bridge(console: ConsoleDep) -> BridgeServer:
    """The simulated vehicle's rosbridge server (it runs whenever the simulator does)."""
    _sim(console)
    assert console.bridge is not None
    return console.bridge


def _given(body: ChannelIn | CurrentIn) -> dict[str, Any]:
    """The fields a PUT sets: those given, and not null (null keeps the current value)."""
    return {k: v for k, v in body.model_dump(exclude_unset=True).items() if v is not None}


@router.get("", response_model=TrainingOn | TrainingOff, response_model_exclude_unset=True)
def training(console: ConsoleDep) -> TrainingOn | TrainingOff:
    """The simulator's settings and its channel's counters (with a fleet, each vehicle's
    receiver's in ``vehicle_channel_stats``, and their sums); ``enabled: false`` on a real
    vehicle."""
    sim = console.sim
    if sim is None:
        return TrainingOff(enabled=False, scenarios=[])
    fleet = console.fleet_sim
    stats = (
        {"channel_stats": ChannelStats.model_validate(asdict(sim.channel.stats))}
        if fleet is None
        else _fleet_stats(fleet)
    )
    return TrainingOn(
        enabled=True,
        channel=_channel(sim),
        current=CurrentSettings.model_validate(asdict(sim.current.config)),
        time_scale=console.bridge.time_scale if console.bridge is not None else 1.0,
        scenarios=list(SCENARIO_PRESETS),
        **stats,
    )


def _fleet_stats(fleet: FleetSimulation) -> dict[str, Any]:
    """``vehicle_channel_stats`` (each vehicle's receiver's counters) and ``channel_stats``
    (their sums) of a fleet's shared link."""
    each = [
        VehicleChannelStats(
            vehicle=v.name,
            address=v.address,
            channel_stats=ChannelStats.model_validate(asdict(fleet.sim(v.name).channel.stats)),
        )
        for v in fleet.vehicles
    ]
    totals = {
        name: sum(getattr(v.channel_stats, name) for v in each)
        for name in ChannelStats.model_fields
    }
    return {
        "channel_stats": ChannelStats.model_validate(totals),
        "vehicle_channel_stats": each,
    }


@router.put("/channel", response_model=ChannelSettings, responses=SETTING)
def channel(body: ChannelIn, console: ConsoleDep, _op: OperatorDep) -> ChannelSettings:
    sim = _sim(console)
    fields = _given(body)
    if "range_m" in body.model_fields_set and body.range_m is None:
        fields["range_m"] = math.inf
    config = replace(sim.channel.config, **fields)
    if console.fleet_sim is not None:  # the one link every vehicle of the fleet shares
        console.fleet_sim.set_channel_config(config)
    else:
        sim.channel.set_config(config)
    return _channel(sim)


@router.put("/current", response_model=CurrentSettings, responses=SETTING)
def current(body: CurrentIn, console: ConsoleDep, _op: OperatorDep) -> CurrentSettings:
    sim = _sim(console)
    config = replace(sim.current.config, **_given(body))
    if console.fleet_sim is not None:  # the water every vehicle of the fleet is in
        console.fleet_sim.set_current_config(config)
    else:
        sim.current.set_config(config)
    return CurrentSettings.model_validate(asdict(sim.current.config))


@router.put("/time_scale", response_model=TimeScale, responses=SETTING)
def time_scale(body: TimeScaleIn, console: ConsoleDep, _op: OperatorDep) -> TimeScale:
    _bridge(console).time_scale = body.time_scale
    return TimeScale(time_scale=body.time_scale)


#: A new dive is written to the mission log first: 503 when it cannot be.
NEW_DIVE = {503: "the mission log cannot be written (the new dive); nothing was changed"}


@router.post(
    "/reset", response_model=NewDive, responses=errors((*OPERATOR, 409, 503), why=NO_SIM | NEW_DIVE)
)
async def reset(console: ConsoleDep, _op: OperatorDep) -> NewDive:
    """The vehicle back to its start pose, a full battery and no command: a new dive. Every
    repetition stops; what was on its way ends ``interrupted``. (On the event loop: it stops
    the delivery tasks.)"""
    _sim(console)
    return NewDive(dive=console.reset_vehicle())


@router.post(
    "/scenario/{name}",
    response_model=ScenarioLoaded,
    response_model_exclude_unset=True,
    responses=errors(
        (*OPERATOR, 404, 409, 422, 429, 503),
        why={
            **NO_SIM,
            **NEW_DIVE,
            404: "no such scenario",
            429: ERROR_TEXT[429] + " (its first command)",
        },
    ),
)
async def scenario(name: str, console: ConsoleDep, _op: OperatorDep) -> ScenarioLoaded:
    """Load one of the paper's scenarios: the vehicle reset to its start, its first command
    sent. The retask is the operator's to send (the preset returns it, ready to preview)."""
    from sim.scenarios import SCENARIOS

    _sim(console)
    if console.fleet_sim is not None:
        raise HTTPException(409, "the paper's scenarios drive one vehicle: not with a fleet")
    if name not in SCENARIOS:
        raise HTTPException(404, f"no scenario {name!r}; choose from {', '.join(SCENARIO_PRESETS)}")
    sc = SCENARIOS[name]
    dive = console.reset_vehicle(start_z_m=sc.start_z_m)
    first, retask = sc.commands[0], sc.commands[sc.retask]
    assert console.service is not None
    request = SendRequest(first.pattern, dict(first.params), "scenario")
    record = (await console.service.send(request)).record
    return ScenarioLoaded(
        dive=dive,
        scenario=name,
        title=sc.title,
        sent=record,
        next=Retask(pattern=retask.pattern, params=dict(retask.params), at_s=retask.t_s),
    )


def _channel(sim: Simulation) -> ChannelSettings:
    """The emulated channel's settings; JSON has no infinity: an unlimited range is null."""
    config = asdict(sim.channel.config)
    return ChannelSettings.model_validate(
        {k: (None if isinstance(v, float) and math.isinf(v) else v) for k, v in config.items()}
    )
