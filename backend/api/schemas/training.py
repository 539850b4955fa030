"""The training controls' documents (the simulated vehicle's channel, current and clock)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from backend.api.schemas.common import Number, Params
from backend.api.schemas.records import CommandRecord


class ChannelSettings(BaseModel):
    """The emulated ME channel."""

    bitrate_bps: Number
    range_m: float | None = Field(description="null: no range limit")
    ber: float
    burst_rate: float
    burst_length_bits: int
    loss: float
    delay_s: float


class CurrentSettings(BaseModel):
    """The water current (NED) and its Gauss-Markov drift."""

    north_mps: float
    east_mps: float
    speed_sigma_mps: float
    direction_sigma_deg: float
    time_constant_s: float
    bound_sigmas: float


class ChannelStats(BaseModel):
    """The emulated channel's counters (with a fleet, :class:`VehicleChannelStats` are each
    vehicle's receiver's)."""

    frames_in: int
    frames_delivered: int
    frames_lost_range: int
    frames_lost_random: int
    bits_sent: int
    bits_flipped: int
    bursts: int


class VehicleChannelStats(BaseModel):
    """One fleet vehicle's receiver on the shared emulated link: every frame reaches every
    vehicle, each through its own channel (its own bit errors, bursts and range)."""

    vehicle: str = Field(description="the fleet's vehicle (NEMESYS_VEHICLES)")
    address: int = Field(description="its frames' address (1-15)")
    channel_stats: ChannelStats = Field(description="its own receiver's counters")


class TrainingOn(BaseModel):
    """Training mode: the simulated vehicle's settings (with a fleet, every vehicle's: they
    share the link's settings and the water)."""

    enabled: Literal[True]
    channel: ChannelSettings
    current: CurrentSettings
    time_scale: float
    scenarios: list[str]
    channel_stats: ChannelStats = Field(
        description="the emulated link's counters; with a fleet, the sums over every "
        "vehicle's receiver (each frame counted once per vehicle: each is in "
        "vehicle_channel_stats)"
    )
    vehicle_channel_stats: list[VehicleChannelStats] | None = Field(
        None,
        description="with a fleet: each vehicle's receiver's counters, in the fleet's order "
        "(absent without a fleet)",
    )


class TrainingOff(BaseModel):
    """A real vehicle: no training controls."""

    enabled: Literal[False]
    scenarios: list[str]


class TimeScale(BaseModel):
    time_scale: float


class NewDive(BaseModel):
    dive: int


class Retask(BaseModel):
    """The scenario's retask, for the operator to preview and send."""

    pattern: str
    params: Params
    at_s: float


class ScenarioLoaded(BaseModel):
    dive: int
    scenario: str
    title: str
    sent: CommandRecord = Field(description="the scenario's first command")
    next: Retask
