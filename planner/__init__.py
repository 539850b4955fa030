"""NemeSys planner: a decoded command -> the 3D path the vehicle flies.

One implementation for the console's preview and the vehicle's execution. Pure Python (no
numpy), so the onboard agent can import it within its memory budget.

Typical use::

    from codec import decode_frame
    from planner import VehicleState, plan
    cmd = decode_frame(bits).command
    p = plan(cmd, VehicleState(x_m=0, y_m=0, z_m=2, heading_deg=90, speed_mps=0.5))
    p.path.xs, p.path.zs, p.path.times
"""

from planner._errors import PlanError
from planner._estimate import Estimate, ParamChange, PlanDiff, compare, estimate
from planner._geometry import CHORD_TOL_M, MAX_STEP_RAD
from planner._limits import (
    DEFAULT_MAX_SPEED_MPS,
    RATED_DEPTH_M,
    CircleFence,
    LimitError,
    Limits,
    PolygonFence,
    Violation,
    check,
    validate,
)
from planner._path import Path, Setpoint, VehicleState
from planner._plan import (
    DEPTH_RATE_MPS,
    HEAVE_CAPABILITY_MPS,
    HOVER_APPROACH_MPS,
    LEAD_TURN_RADII,
    MAX_WAYPOINTS,
    MIN_TURN_RADIUS_M,
    ORBIT_PATTERNS,
    REPEATING_PATTERNS,
    YAW_RATE_DPS,
    Plan,
    anchor_for,
    plan,
    turn_radius_m,
)

__all__ = [
    "CHORD_TOL_M",
    "DEFAULT_MAX_SPEED_MPS",
    "DEPTH_RATE_MPS",
    "HEAVE_CAPABILITY_MPS",
    "HOVER_APPROACH_MPS",
    "LEAD_TURN_RADII",
    "MAX_STEP_RAD",
    "MAX_WAYPOINTS",
    "MIN_TURN_RADIUS_M",
    "ORBIT_PATTERNS",
    "RATED_DEPTH_M",
    "REPEATING_PATTERNS",
    "YAW_RATE_DPS",
    "CircleFence",
    "Estimate",
    "LimitError",
    "Limits",
    "ParamChange",
    "Path",
    "Plan",
    "PlanDiff",
    "PlanError",
    "PolygonFence",
    "Setpoint",
    "VehicleState",
    "Violation",
    "anchor_for",
    "check",
    "compare",
    "estimate",
    "plan",
    "turn_radius_m",
    "validate",
]
