"""The console's checks of a plan before a send: :func:`check` raises :class:`LimitError`
unless every violation is overridable and the operator overrides explicitly, and
:func:`top_speed` compares the plan with the vehicle's top speed through the water.

The vehicle only validates (:func:`planner.validate`) and never loads this module.
"""

from __future__ import annotations

from planner._limits import Limits, Violation, validate

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Sequence

    from planner._estimate import Estimate
    from planner._plan import Plan


class LimitError(ValueError):
    """A plan breaks limits and was not (or cannot be) overridden."""

    def __init__(self, violations: Sequence[Violation]) -> None:
        self.violations = tuple(violations)
        super().__init__("; ".join(v.message for v in self.violations))


def check(plan: Plan, limits: Limits, override: bool = False) -> tuple[Violation, ...]:
    """Violations of ``plan``; raises unless there are none or the operator overrides.

    Returns:
        The violations that were overridden (empty if there were none).

    Raises:
        LimitError: there are violations and ``override`` is false, or one of them (the depth
            rating) cannot be overridden.
    """
    found = validate(plan, limits)
    if found and (not override or any(not v.overridable for v in found)):
        raise LimitError(found)
    return found


def top_speed(
    plan: Plan, top_speed_mps: float | None, est: Estimate | None = None
) -> Violation | None:
    """The violation of a plan asking for more than the vehicle's top speed (m/s), or
    ``None`` (also when the top speed is unknown, or the plan never moves horizontally).

    Only a commanded ``speed`` is checked: a pattern without one (hover's approach at the
    planner's own pace) asks the operator for nothing to override, and the vehicle flies it
    as fast as it can (the estimate's duration says how long). Overridable: the vehicle flies
    a commanded speed above its top speed at top speed, only slower.
    """
    from planner._estimate import estimate

    commanded = plan.command.params.get("speed")
    speed = float(commanded) if isinstance(commanded, int | float) else None
    if top_speed_mps is None or speed is None or speed <= top_speed_mps:
        return None
    if est is None:  # the plan's estimate at the flyable speed, when not given
        est = estimate(plan, top_speed_mps)
    planned = est.planned_duration_s
    ratio = est.duration_s / planned if planned > 0 else speed / top_speed_mps
    top = f"{round(top_speed_mps, 2):g}"
    return Violation(
        "speed",
        speed,
        top_speed_mps,
        "m/s",
        f"speed {round(speed, 3):g} m/s exceeds the vehicle's {top} m/s top speed: it will "
        f"fly at {top} m/s, {ratio:.1f}x the planned duration",
    )
