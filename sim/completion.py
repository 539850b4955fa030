"""When the pattern guidance flies is *done*: the one rule the training twin, the kinematic
twin (the preview's estimate, :mod:`sim.kinematic`), the prediction and the console's reading
of a vehicle's status (:func:`backend.scripts.completion.vehicle_verdict`) all time a command by.

* A **finite** pattern is done when guidance reports it so, in the mode the vehicle's status
  carries (:func:`done_mode`): ``holding`` (a surface: ``surfaced``). Guidance holds at the
  path's end (a hover: when its time is up) and reports ``holding`` only once the vehicle is
  at the held depth, within :data:`AT_DEPTH_M` (:mod:`onboard.guidance`): a depth change the
  path leaves for the end (its ramp outlasting the horizontal path) is flown in place first,
  and a vehicle still 7 m above its depth has not done its command (issue 20: a prediction
  "done" at 76 s for a vehicle that reached its depth at 160 s).
* A **repeating** pattern (square, circle) never ends: it is done with the join and one lap,
  when guidance wraps from the path's last segment into its lap (what the estimate's
  ``duration_s`` of a repeating pattern covers).

Only guidance's own state is read, so a vehicle running the real onboard guidance reports the
same in its status.
"""

from __future__ import annotations

from onboard.guidance import AT_DEPTH_M, Guidance
from planner import Plan
from vehicle_contract.codes import Mode

__all__ = ["AT_DEPTH_M", "Completion", "done_mode"]


def done_mode(pattern: str) -> Mode:
    """The mode guidance (and so the vehicle's status) reports once a finite ``pattern`` is
    done: a surface at the surface, any other pattern holding the end of its path at its
    depth (a hover: after its duration)."""
    return Mode.SURFACED if pattern == "surface" else Mode.HOLDING


class Completion:
    """Follows one guidance, tick by tick; :attr:`done_s` is when its plan was done (s, the
    clock given to :meth:`update`), ``None`` until then. A new plan starts it afresh."""

    __slots__ = ("_segment", "done_s", "plan")

    def __init__(self) -> None:
        #: The plan being timed (guidance's), None before the first.
        self.plan: Plan | None = None
        self.done_s: float | None = None
        self._segment = 0

    def update(self, guidance: Guidance, t_s: float) -> float | None:
        """Look at ``guidance`` after its tick at ``t_s`` (s); returns :attr:`done_s`."""
        plan = guidance.plan
        if plan is not self.plan:
            self.plan, self.done_s, self._segment = plan, None, guidance.segment
        if plan is None or self.done_s is not None:
            return self.done_s
        if plan.path.loop_start is not None:
            if guidance.mode is Mode.RUNNING:
                if guidance.segment < self._segment:  # wrapped into the lap: one lap flown
                    self.done_s = t_s
                self._segment = guidance.segment
        elif guidance.mode is done_mode(plan.pattern):
            self.done_s = t_s
        return self.done_s
