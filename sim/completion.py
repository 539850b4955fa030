"""When the pattern guidance flies is *done*: the one rule the training twin, the kinematic
twin (the preview's estimate, :mod:`sim.kinematic`) and the prediction all time a command by.

* A **finite** pattern is done when guidance holds at the path's end (a hover: when its time
  is up) or has surfaced, *and* the vehicle is at the held depth, within :data:`AT_DEPTH_M`.
  Guidance finishes a path when the vehicle reaches its horizontal end; a depth change the path
  leaves for the end (its ramp outlasting the horizontal path) is then flown in place, and a
  vehicle still 7 m above its depth has not done its command (issue 20: a prediction "done" at
  76 s for a vehicle that reached its depth at 160 s).
* A **repeating** pattern (square, circle) never ends: it is done with the join and one lap,
  when guidance wraps from the path's last segment into its lap (what the estimate's
  ``duration_s`` of a repeating pattern covers).

Only guidance's own state and the depth are read, so a vehicle running the real onboard
guidance could report the same.
"""

from __future__ import annotations

from onboard.guidance import Guidance
from planner import Plan
from vehicle_contract.codes import Mode

#: The vehicle is at the held depth within this (m): the depth loop holds +-3 cm (the paper's
#: tank test), the depth sensor adds its noise.
AT_DEPTH_M = 0.1

_ENDED = (Mode.HOLDING, Mode.SURFACED)


class Completion:
    """Follows one guidance, tick by tick; :attr:`done_s` is when its plan was done (s, the
    clock given to :meth:`update`), ``None`` until then. A new plan starts it afresh."""

    __slots__ = ("_segment", "done_s", "plan")

    def __init__(self) -> None:
        #: The plan being timed (guidance's), None before the first.
        self.plan: Plan | None = None
        self.done_s: float | None = None
        self._segment = 0

    def update(self, guidance: Guidance, z_m: float, t_s: float) -> float | None:
        """Look at ``guidance`` after its tick at ``t_s`` (s) with the vehicle at depth ``z_m``
        (m); returns :attr:`done_s`."""
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
        elif guidance.mode in _ENDED and abs(z_m - guidance.hold[2]) <= AT_DEPTH_M:
            self.done_s = t_s
        return self.done_s
