"""The simulated vehicle's surroundings and onboard supplies: current, depth sensor, battery.

Pure Python (``math`` and a seeded :class:`random.Random` each), cheap per call: the simulated
vehicle steps these at 50 Hz for up to 20 vehicles. Same seed, same calls, same results. SI
units, NED frame (north, east, down); depth is positive down.

* :class:`Current`: a constant NED water current plus an optional first-order Gauss-Markov drift
  of its speed and direction, bounded.
* :class:`DepthSensor`: a Bar30 (MS5837-30BA) pressure sensor: 2 mm steps, Gaussian noise,
  20 Hz sample-and-hold.
* :class:`Battery`: the paper's state-of-charge curve (100/71/54/42/32/22 % after 0..5 h),
  made to respond to thruster load.

Sources: the research note ``sim.md`` sections 2.1-2.5 (Fossen ch. 8 for the Gauss-Markov
current; the MS5837-30BA datasheet for 0.2 mbar = 2 mm resolution; the battery fit).

One module each (:mod:`sim.environment.current`, :mod:`sim.environment.depth_sensor`,
:mod:`sim.environment.battery`); every name is importable from here.
"""

from sim.environment.battery import (
    CALIBRATED_THRUST_N,
    HOTEL_POWER_W,
    NOMINAL_THRUST_POWER_W,
    NOMINAL_THRUSTS_N,
    PAPER_SOC_TABLE,
    SOC_FAST_PCT,
    SOC_FAST_TAU_H,
    SOC_LINEAR_PCT_PER_H,
    THRUST_POWER_COEFF_W_PER_N1_5,
    Battery,
    BatteryConfig,
    paper_soc_pct,
    thrust_power_w,
)
from sim.environment.current import MAX_CURRENT_MPS, Current, CurrentConfig
from sim.environment.depth_sensor import BAR30_QUANTUM_M, DepthSensor, DepthSensorConfig

__all__ = [
    "BAR30_QUANTUM_M",
    "CALIBRATED_THRUST_N",
    "HOTEL_POWER_W",
    "MAX_CURRENT_MPS",
    "NOMINAL_THRUSTS_N",
    "NOMINAL_THRUST_POWER_W",
    "PAPER_SOC_TABLE",
    "SOC_FAST_PCT",
    "SOC_FAST_TAU_H",
    "SOC_LINEAR_PCT_PER_H",
    "THRUST_POWER_COEFF_W_PER_N1_5",
    "Battery",
    "BatteryConfig",
    "Current",
    "CurrentConfig",
    "DepthSensor",
    "DepthSensorConfig",
    "paper_soc_pct",
    "thrust_power_w",
]
