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
from planner._geometry import CHORD_TOL_M, MAX_STEP_RAD
from planner._path import Path, VehicleState
from planner._plan import (
    DEPTH_RATE_MPS,
    HEAVE_CAPABILITY_MPS,
    HOVER_APPROACH_MPS,
    LEAD_TURN_RADII,
    MAX_WAYPOINTS,
    MIN_TURN_RADIUS_M,
    REPEATING_PATTERNS,
    YAW_RATE_DPS,
    Plan,
    anchor_for,
    plan,
    turn_radius_m,
)

TYPE_CHECKING = False
if TYPE_CHECKING:
    from planner._checks import LimitError, check
    from planner._estimate import Estimate, ParamChange, PlanDiff, compare, estimate
    from planner._fence import CircleFence, PolygonFence
    from planner._limits import (
        DEFAULT_MAX_SPEED_MPS,
        RATED_DEPTH_M,
        Limits,
        Violation,
        validate,
    )
    from planner._sampling import Setpoint

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

# Imported on first use: estimates, sampling, geofences and the console's checks are the
# console's; the vehicle's decode-and-replan loop needs only the limits' validation, which the
# agent imports (``nemesys bench reconfig`` measures its footprint). Hidden from the type
# checker, which sees the imports above.
_LAZY = {
    "Setpoint": "_sampling",
    "Estimate": "_estimate",
    "ParamChange": "_estimate",
    "PlanDiff": "_estimate",
    "compare": "_estimate",
    "estimate": "_estimate",
    "DEFAULT_MAX_SPEED_MPS": "_limits",
    "RATED_DEPTH_M": "_limits",
    "CircleFence": "_fence",
    "LimitError": "_checks",
    "Limits": "_limits",
    "PolygonFence": "_fence",
    "Violation": "_limits",
    "check": "_checks",
    "validate": "_limits",
}

if not TYPE_CHECKING:

    def __getattr__(name: str) -> object:
        module = _LAZY.get(name)
        if module is None:
            raise AttributeError(f"module 'planner' has no attribute {name!r}")
        import sys

        __import__(f"planner.{module}")  # not importlib: it loads warnings (onboard path)
        value = getattr(sys.modules[f"planner.{module}"], name)
        globals()[name] = value
        return value
