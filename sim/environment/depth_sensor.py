"""The depth sensor: a Bar30 (MS5837-30BA) pressure sensor, 2 mm steps, Gaussian noise, 20 Hz
sample-and-hold (the research note ``sim.md`` 2.2; the MS5837-30BA datasheet for 0.2 mbar =
2 mm resolution). Seeded :class:`random.Random`; depth positive down.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from sim._checks import in_range, positive

#: MS5837-30BA resolution: 0.2 mbar at the finest oversampling, 2 mm of seawater.
BAR30_QUANTUM_M = 0.002


@dataclass(frozen=True, slots=True)
class DepthSensorConfig:
    """A Bar30 (MS5837-30BA) depth sensor."""

    #: Standard deviation of the Gaussian noise (m), in [0, 1].
    noise_sigma_m: float = 0.002
    #: Reading resolution (m), in [0, 1]; 0 for none.
    quantum_m: float = BAR30_QUANTUM_M
    #: Sample rate (Hz), in (0, inf), or None for a new sample on every read.
    rate_hz: float | None = 20.0

    def __post_init__(self) -> None:
        in_range("noise_sigma_m", self.noise_sigma_m, 0.0, 1.0, "[0, 1]")
        in_range("quantum_m", self.quantum_m, 0.0, 1.0, "[0, 1]")
        if self.rate_hz is not None:
            positive("rate_hz", self.rate_hz)


class DepthSensor:
    """Reads depth like a Bar30: noisy, quantised, sampled at its rate and held in between.

    Samples are taken on the grid ``t = k / rate_hz``: a read in a new grid interval (or the
    first read) takes a sample, any other read returns the held one. A sample is
    ``q * round((max(true, 0) + noise) / q)``. Above the surface (negative true depth) the
    sensor sees atmospheric pressure, which the zeroed sensor reads as depth 0, so it reads 0
    plus noise, a few millimetres either side of 0 as a real zeroed Bar30 in air does.
    """

    __slots__ = ("_config", "_k", "_reading_m", "_rng", "_sample_t_s", "samples")

    def __init__(self, config: DepthSensorConfig | None = None, seed: int = 0) -> None:
        self._rng = random.Random(seed)
        self._reading_m = 0.0
        self._sample_t_s = math.nan
        #: How many samples have been taken.
        self.samples = 0
        self.set_config(config if config is not None else DepthSensorConfig())

    @property
    def config(self) -> DepthSensorConfig:
        return self._config

    def set_config(self, config: DepthSensorConfig) -> None:
        """Change the sensor's settings; the next read takes a new sample."""
        if not isinstance(config, DepthSensorConfig):
            raise TypeError(f"config must be a DepthSensorConfig, got {type(config).__name__}")
        self._config = config
        self._k: int | None = None

    def read(self, true_depth_m: float, t_s: float) -> float:
        """The reading (m, positive down) at simulated time ``t_s`` for the true depth."""
        if math.isnan(true_depth_m):
            raise ValueError("true_depth_m is NaN")
        cfg = self._config
        rate = cfg.rate_hz
        if rate is not None:
            # The epsilon puts t = k / rate in slot k even when the clock adds up to a hair less
            # (ten steps of 0.02 s make 0.19999999999999998 s).
            k = math.floor(t_s * rate + 1e-9)
            if k == self._k:
                return self._reading_m
            self._k = k
        depth = true_depth_m if true_depth_m > 0.0 else 0.0
        if cfg.noise_sigma_m > 0.0:
            depth += cfg.noise_sigma_m * self._rng.gauss(0.0, 1.0)
        q = cfg.quantum_m
        if q > 0.0:
            depth = round(depth / q) * q
        self._reading_m = depth
        self._sample_t_s = t_s
        self.samples += 1
        return depth

    @property
    def last_reading_m(self) -> float:
        """The held reading (0.0 before the first read)."""
        return self._reading_m

    @property
    def last_sample_t_s(self) -> float:
        """When the held reading was sampled (NaN before the first read)."""
        return self._sample_t_s
