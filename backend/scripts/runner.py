"""Mission scripts, run: the state machine the console drives while a script runs.

Completion is detected by the plan, on the run clock (why: :mod:`backend.scripts.completion`):
a step "on completion" is due the previous step's planned completion time after the previous
step was handed out for sending, so the run sends at the times the timeline and the onboard
export show.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal

from backend.scripts.completion import after_repeating
from backend.scripts.expand import ExpandedStep, expand
from backend.scripts.model import MissionScript, RunMode, StepState, WaitingFor
from planner import VehicleState

#: Tolerance of the due-time comparisons (s).
EPS_S = 1e-9


class ScriptRunError(RuntimeError):
    """A runner call that does not fit its state (e.g. ``go()`` with nothing proposed)."""


class ScriptRunner:
    """The state machine of a script run; no I/O.

    The console calls :meth:`poll` with the run clock (``now_s``, vehicle seconds; or a
    ``clock`` given to the constructor), sends the steps it returns (or the one :meth:`go`
    releases) and reports back with :meth:`mark_sent`, :meth:`mark_acknowledged` or
    :meth:`mark_failed`.

    Rules:

    * a step is due only after the previous one is acknowledged, and is handed out once
      (by :meth:`poll` or :meth:`go`), never twice;
    * ``mode="auto"``: ``at`` steps are due when ``now_s - start_s >= t_s`` (``start_s``:
      the constructor's, else the first poll's ``now_s``); ``after_previous`` steps
      ``completion_s[i - 1]`` after step ``i - 1`` was handed out (its planned completion:
      the end of its path, a hover's duration); ``operator`` steps are proposed and wait for
      :meth:`go`;
    * ``mode="step"``: every step is proposed and waits for :meth:`go`;
    * :meth:`mark_failed` and :meth:`stop` end the run; it also ends when every step is
      acknowledged.

    A run never waits on the vehicle: the longest wait for a completion is the previous
    step's planned completion time. A handed-out step shows as ``sent`` (``transmitted``
    false until :meth:`mark_sent`).

    Args:
        script: a validated script.
        mode: ``auto`` or ``step``.
        completion_s: each step's completion time (s after it takes effect; ``None``: it
            repeats), from the expansion the run was planned with
            (:meth:`ScriptRunner.planned` gives them). Default: the script expanded from the
            NED origin at the surface, at rest.
        start_s: the run clock at the start (default: the first poll's).
        clock: the run clock (s), read when :meth:`poll` or :meth:`go` get no ``now_s``.

    Raises:
        ValueError: an unknown mode, ``completion_s`` of the wrong length, or a step "on
            completion" after one that never completes (a script built without validation).
    """

    def __init__(
        self,
        script: MissionScript,
        mode: RunMode = "auto",
        *,
        completion_s: Sequence[float | None] | None = None,
        start_s: float | None = None,
        clock: Callable[[], float] | None = None,
    ) -> None:
        if mode not in ("auto", "step"):
            raise ValueError(f"run mode must be 'auto' or 'step', got {mode!r}")
        n = len(script.steps)
        if completion_s is None:
            completion_s = [s.completion_s for s in expand(script, VehicleState(0.0, 0.0, 0.0))]
        if len(completion_s) != n:
            raise ValueError(f"completion_s has {len(completion_s)} times for {n} steps")
        for i in range(1, n):
            if script.steps[i].trigger.kind == "after_previous" and completion_s[i - 1] is None:
                raise ValueError(after_repeating(i, script.steps[i - 1].pattern))
        self.script = script
        self.mode: RunMode = mode
        self.completion_s: tuple[float | None, ...] = tuple(completion_s)
        self.start_s = start_s
        self.clock = clock
        self.now_s: float | None = None
        self.running = True
        self.outcome: Literal["running", "completed", "stopped", "failed"] = "running"
        self.reason: str | None = None
        self._states: list[StepState] = ["pending"] * n
        self._transmitted = [False] * n
        self._handed_at: list[float | None] = [None] * n  # run clock when handed out
        self._next = 0  # the first step not yet handed out

    @classmethod
    def planned(
        cls,
        script: MissionScript,
        expanded: Sequence[ExpandedStep],
        mode: RunMode = "auto",
        *,
        clock: Callable[[], float] | None = None,
    ) -> ScriptRunner:
        """A runner timed by ``expanded`` (:func:`backend.scripts.expand.expand` of
        ``script`` from where the vehicle is), as the preview and the export are."""
        return cls(script, mode, completion_s=[s.completion_s for s in expanded], clock=clock)

    # --- queries --------------------------------------------------------------------------

    @property
    def next_index(self) -> int | None:
        """The next step to hand out, or ``None`` when every step has been."""
        return self._next if self._next < len(self.script.steps) else None

    def step_state(self, i: int) -> StepState:
        """Step ``i``'s state: pending, sent, acknowledged or failed."""
        return self._states[i]

    def _previous_acknowledged(self) -> bool:
        return self._next == 0 or self._states[self._next - 1] == "acknowledged"

    def waiting_for(self) -> WaitingFor | None:
        """What the next step waits for, or ``None`` when the run is over."""
        i = self.next_index
        if not self.running:
            return None
        if not self._previous_acknowledged():
            return "acknowledgement"
        if i is None:  # pragma: no cover - the run ends when the last step is acknowledged
            return None
        kind = self.script.steps[i].trigger.kind
        if self.mode == "step" or kind == "operator":
            return "operator"
        return "time" if kind == "at" else "completion"

    def proposed(self) -> int | None:
        """The step awaiting the operator's go, if any (step mode: every step; auto mode:
        ``operator`` steps), once the previous one is acknowledged."""
        return self.next_index if self.waiting_for() == "operator" else None

    def due_s(self) -> float | None:
        """For an ``at`` or ``after_previous`` step in auto mode: when it is due (run clock),
        if known (acknowledgement of the previous step still needed)."""
        i = self.next_index
        if i is None or self.mode != "auto" or self.start_s is None:
            return None
        t = self.script.steps[i].trigger
        if t.kind == "at" and t.t_s is not None:
            return self.start_s + t.t_s
        if t.kind == "after_previous" and i > 0:
            handed, done = self._handed_at[i - 1], self.completion_s[i - 1]
            return None if handed is None or done is None else handed + done
        return None

    def _rel(self, t: float | None) -> float | None:
        """A run-clock value as seconds from the run's start."""
        return None if t is None or self.start_s is None else round(t - self.start_s, 3)

    def state(self) -> dict[str, Any]:
        """The run as JSON: ``{running, mode, outcome, name, step, next, waiting_for, due_s,
        elapsed_s, steps: [{index, pattern, trigger, state, transmitted, sent_s,
        completion_s}], reason}``; times in s from the run's start."""
        proposed = self.proposed()
        nxt: dict[str, Any] | None = None
        if proposed is not None:
            s = self.script.steps[proposed]
            nxt = {
                "index": proposed,
                "pattern": s.pattern,
                "params": dict(s.params),
                "trigger": s.trigger.model_dump(),
            }
        return {
            "running": self.running,
            "mode": self.mode,
            "outcome": self.outcome,
            "name": self.script.name,
            "step": self.next_index,
            "next": nxt,
            "waiting_for": self.waiting_for(),
            "due_s": self._rel(self.due_s()) if self.running else None,
            "elapsed_s": self._rel(self.now_s),
            "steps": [
                {
                    "index": i,
                    "pattern": s.pattern,
                    "trigger": s.trigger.kind,
                    "state": self._states[i],
                    "transmitted": self._transmitted[i],
                    "sent_s": self._rel(self._handed_at[i]),
                    "completion_s": self.completion_s[i],
                }
                for i, s in enumerate(self.script.steps)
            ],
            "reason": self.reason,
        }

    # --- driving --------------------------------------------------------------------------

    def _now(self, now_s: float | None) -> float:
        if now_s is not None:
            return now_s
        if self.clock is not None:
            return self.clock()
        if self.now_s is not None:
            return self.now_s
        raise ScriptRunError("the run has no clock: give now_s")

    def poll(self, now_s: float | None = None) -> list[int]:
        """The steps to send now (auto mode; at most one, as each waits for the previous
        acknowledgement). ``now_s``: the run clock (s; default: the constructor's clock)."""
        now = self._now(now_s)
        if self.start_s is None:
            self.start_s = now
        self.now_s = now
        i = self.next_index
        if not self.running or i is None or not self._previous_acknowledged():
            return []
        if self.mode != "auto":
            return []
        due = self.due_s()
        if due is None or now < due - EPS_S:
            return []
        self._hand_out(i, now)
        return [i]

    def go(self, now_s: float | None = None) -> int:
        """The operator confirms the proposed step: returns its index, to send.

        Raises:
            ScriptRunError: nothing is proposed (the run is over, the previous step is not
                acknowledged yet, or in auto mode the next step is not an ``operator`` one).
        """
        i = self.proposed()
        if i is None:
            why = self.waiting_for()
            raise ScriptRunError(
                "no step awaits the operator"
                + (f": the run is waiting for {why}" if why else ": the run is over")
            )
        now = now_s if now_s is not None else self.clock() if self.clock else self.now_s
        if now is not None:
            if self.start_s is None:
                self.start_s = now
            self.now_s = now
        self._hand_out(i, now)
        return i

    def _hand_out(self, i: int, now: float | None) -> None:
        self._states[i] = "sent"
        self._handed_at[i] = now
        self._next = i + 1

    def _check_handed_out(self, i: int, what: str) -> None:
        if not 0 <= i < len(self._states):
            raise ScriptRunError(f"{what}: the script has no step {i}")
        if self._states[i] == "pending":
            raise ScriptRunError(f"{what}: step {i} has not been handed out for sending")

    def mark_sent(self, i: int) -> None:
        """Step ``i`` left the station."""
        self._check_handed_out(i, "mark_sent")
        self._transmitted[i] = True

    def mark_acknowledged(self, i: int) -> None:
        """The vehicle accepted step ``i``; the run ends when it is the last step."""
        self._check_handed_out(i, "mark_acknowledged")
        if self._states[i] in ("failed", "acknowledged"):
            return
        self._states[i] = "acknowledged"
        self._transmitted[i] = True
        if self.running and all(s == "acknowledged" for s in self._states):
            self.running = False
            self.outcome = "completed"

    def mark_failed(self, i: int, reason: str) -> None:
        """Step ``i`` could not be delivered (failed, rejected, timed out): the run stops."""
        self._check_handed_out(i, "mark_failed")
        self._states[i] = "failed"
        if self.running:
            self.running = False
            self.outcome = "failed"
            self.reason = f"step {i + 1} ({self.script.steps[i].pattern}) failed: {reason}"

    def stop(self, reason: str = "stopped by the operator") -> None:
        """End the run; nothing more is handed out."""
        if self.running:
            self.running = False
            self.outcome = "stopped"
            self.reason = reason
