"""Mission scripts, run: the state machine the console drives while a script runs.

A step "on completion" is timed by the plan, on the run clock (why:
:mod:`backend.scripts.completion`): it is due the previous step's planned completion time after
the previous step was handed out for sending, so the run sends at the times the timeline shows.
The run itself is over when its last step's pattern completes, as the vehicle reports it, or
where the link reports nothing, by the plan (estimated); a repeating last step leaves the
vehicle "running until retasked".
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal

from backend.scripts.completion import after_repeating, flyable_s, vehicle_verdict
from backend.scripts.expand import ExpandedStep, expand
from backend.scripts.labels import describe_steps, run_summary
from backend.scripts.model import MissionScript, RunMode, StepState, WaitingFor
from codec import decode_frame, encode_frame
from planner import VehicleState

Outcome = Literal["running", "completed", "until_retasked", "stopped", "failed"]
#: How the run knows its last step completed: the vehicle's status, or the plan (estimated).
CompletionBy = Literal["vehicle", "plan"]

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
    * :meth:`mark_failed` and :meth:`stop` end the run;
    * once every step is acknowledged the run ends when the last step's pattern completes:
      with ``completion_by="vehicle"`` when a status fed to :meth:`observe` says so (a status
      saying the step will not complete, a retask or an empty battery, stops the run); with
      ``"plan"`` (a link that reports nothing) :meth:`poll` ends it ``flyable_s`` after the
      step was handed out, an estimate; a repeating last step ends it at once, the vehicle
      ``until_retasked``.

    A step "on completion" never waits on the vehicle: the longest wait is the previous
    step's planned completion time. A handed-out step shows as ``sent`` (``transmitted``
    false until :meth:`mark_sent`).

    Args:
        script: a validated script.
        mode: ``auto`` or ``step``.
        completion_s: each step's completion time (s after it takes effect; ``None``: it
            repeats), from the expansion the run was planned with
            (:meth:`ScriptRunner.planned` gives them). Default: the script expanded from the
            NED origin at the surface, at rest.
        flyable_s: each step's duration at the speed the vehicle can fly (s; ``None``: it
            repeats), the estimate a link that reports nothing ends the run by. Default:
            ``completion_s``.
        start_s: the run clock at the start (default: the first poll's).
        clock: the run clock (s), read when :meth:`poll` or :meth:`go` get no ``now_s``.
        completion_by: how the last step's completion is known (the caller may change
            :attr:`completion_by` while the run goes, as the link's capability becomes known).

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
        flyable_s: Sequence[float | None] | None = None,
        start_s: float | None = None,
        clock: Callable[[], float] | None = None,
        completion_by: CompletionBy = "plan",
    ) -> None:
        if mode not in ("auto", "step"):
            raise ValueError(f"run mode must be 'auto' or 'step', got {mode!r}")
        n = len(script.steps)
        if completion_s is None:
            completion_s = [s.completion_s for s in expand(script, VehicleState(0.0, 0.0, 0.0))]
        if flyable_s is None:
            flyable_s = completion_s
        for name, times in (("completion_s", completion_s), ("flyable_s", flyable_s)):
            if len(times) != n:
                raise ValueError(f"{name} has {len(times)} times for {n} steps")
        for i in range(1, n):
            if script.steps[i].trigger.kind == "after_previous" and completion_s[i - 1] is None:
                raise ValueError(after_repeating(i, script.steps[i - 1].pattern))
        self.script = script
        self.mode: RunMode = mode
        self.completion_s: tuple[float | None, ...] = tuple(completion_s)
        self.flyable_s: tuple[float | None, ...] = tuple(flyable_s)
        self.start_s = start_s
        self.clock = clock
        self.completion_by: CompletionBy = completion_by
        self.now_s: float | None = None
        self.running = True
        self.outcome: Outcome = "running"
        self.reason: str | None = None
        #: When the last step completed (run clock), as the vehicle reported or estimated.
        self.completed_at: float | None = None
        self._states: list[StepState] = ["pending"] * n
        self._transmitted = [False] * n
        self._by_vehicle = [False] * n  # acknowledged by the vehicle itself
        self._acked_t_s: list[float | None] = [None] * n  # vehicle time of the acceptance
        self._handed_at: list[float | None] = [None] * n  # run clock when handed out
        self._next = 0  # the first step not yet handed out
        # each step's command as the vehicle decodes it (what its status names)
        self._commands = [
            decode_frame(encode_frame(s.pattern, s.params).frame.bits).command for s in script.steps
        ]

    @classmethod
    def planned(
        cls,
        script: MissionScript,
        expanded: Sequence[ExpandedStep],
        mode: RunMode = "auto",
        *,
        clock: Callable[[], float] | None = None,
        top_speed_mps: float | None = None,
        heave_rate_mps: float | None = None,
        completion_by: CompletionBy = "plan",
    ) -> ScriptRunner:
        """A runner timed by ``expanded`` (:func:`backend.scripts.expand.expand` of
        ``script`` from where the vehicle is), as the preview is; the steps' flyable
        durations at the vehicle's ``top_speed_mps`` and ``heave_rate_mps`` (unknown: as
        planned)."""
        return cls(
            script,
            mode,
            completion_s=[s.completion_s for s in expanded],
            flyable_s=[flyable_s(s.plan, top_speed_mps, heave_rate_mps) for s in expanded],
            clock=clock,
            completion_by=completion_by,
        )

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
        if i is None:  # every step acknowledged: the last one's pattern is still flying
            return "completion"
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
        if known (acknowledgement of the previous step still needed); once every step is
        handed out, when the last one is expected to complete (its flyable duration after it
        was handed out)."""
        i = self.next_index
        if i is None:
            return self._last_expected_s()
        if self.mode != "auto" or self.start_s is None:
            return None
        t = self.script.steps[i].trigger
        if t.kind == "at" and t.t_s is not None:
            return self.start_s + t.t_s
        if t.kind == "after_previous" and i > 0:
            handed, done = self._handed_at[i - 1], self.completion_s[i - 1]
            return None if handed is None or done is None else handed + done
        return None

    def _last_expected_s(self) -> float | None:
        last = len(self._states) - 1
        handed, takes = self._handed_at[last], self.flyable_s[last]
        return None if handed is None or takes is None else handed + takes

    def _rel(self, t: float | None) -> float | None:
        """A run-clock value as seconds from the run's start."""
        return None if t is None or self.start_s is None else round(t - self.start_s, 3)

    def state(self) -> dict[str, Any]:
        """The run as JSON: ``{running, mode, outcome, name, step, next, waiting_for, due_s,
        elapsed_s, completion_by, completed_s, steps: [{index, pattern, trigger, t_s, state,
        transmitted, acknowledged_by_vehicle, sent_s, completion_s, completed_s, and the
        texts}], reason, summary}``; times in s from the run's start, the texts in words
        (:mod:`backend.scripts.labels`)."""
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
        last = len(self._states) - 1
        steps = [
            {
                "index": i,
                "pattern": s.pattern,
                "trigger": s.trigger.kind,
                "t_s": s.trigger.t_s,
                "state": self._states[i],
                "transmitted": self._transmitted[i],
                "acknowledged_by_vehicle": self._by_vehicle[i],
                "sent_s": self._rel(self._handed_at[i]),
                "completion_s": self.completion_s[i],
                "completed_s": self._rel(self.completed_at) if i == last else None,
            }
            for i, s in enumerate(self.script.steps)
        ]
        describe_steps(steps, self.completion_by)
        doc = {
            "running": self.running,
            "mode": self.mode,
            "outcome": self.outcome,
            "name": self.script.name,
            "step": self.next_index,
            "next": nxt,
            "waiting_for": self.waiting_for(),
            "due_s": self._rel(self.due_s()) if self.running else None,
            "elapsed_s": self._rel(self.now_s),
            "completion_by": self.completion_by,
            "completed_s": self._rel(self.completed_at),
            "steps": steps,
            "reason": self.reason,
        }
        doc["summary"] = run_summary(doc)
        return doc

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
        acknowledgement). ``now_s``: the run clock (s; default: the constructor's clock).
        With ``completion_by="plan"`` it also ends the run when the last step is estimated
        complete."""
        now = self._now(now_s)
        if self.start_s is None:
            self.start_s = now
        self.now_s = now
        i = self.next_index
        if self.running and i is None and self.completion_by == "plan":
            expected = self._last_expected_s()
            if self._previous_acknowledged() and expected is not None and now >= expected - EPS_S:
                self._complete(expected)
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

    def mark_acknowledged(
        self, i: int, *, by_vehicle: bool = True, vehicle_t_s: float | None = None
    ) -> None:
        """Step ``i`` is on its way for good: the vehicle accepted it (``by_vehicle``, at
        vehicle time ``vehicle_t_s`` when known), or on a link without acknowledgements its
        last copy left. When it is the last step and it repeats, the run ends (the vehicle
        runs it until retasked); a finite last step ends the run when it completes."""
        self._check_handed_out(i, "mark_acknowledged")
        if self._states[i] in ("failed", "acknowledged"):
            return
        self._states[i] = "acknowledged"
        self._transmitted[i] = True
        self._by_vehicle[i] = by_vehicle
        self._acked_t_s[i] = vehicle_t_s
        every = all(s == "acknowledged" for s in self._states)
        if self.running and every and None in (self.flyable_s[-1], self.completion_s[-1]):
            self.running = False  # the last step repeats: nothing more to wait for
            self.outcome = "until_retasked"

    def observe(self, status: Mapping[str, Any] | None) -> None:
        """The vehicle's latest status (``completion_by="vehicle"``): once every step is
        acknowledged, the run completes when it reports the last step complete, and stops
        when it reports that step will not complete (retasked, battery empty)."""
        last = len(self._states) - 1
        waiting = self.running and self.next_index is None and self._previous_acknowledged()
        if not waiting or self.completion_by != "vehicle":
            return
        command = self._commands[last]
        verdict, why = vehicle_verdict(
            status, command.pattern.name, command.params, self._acked_t_s[last]
        )
        if verdict == "complete":
            self._complete(self.clock() if self.clock is not None else self.now_s)
        elif verdict == "ended":
            pattern = self.script.steps[last].pattern
            self.stop(f"step {last + 1} ({pattern}) will not complete: {why}")

    def _complete(self, at: float | None) -> None:
        self.running = False
        self.outcome = "completed"
        self.completed_at = at

    def mark_failed(self, i: int, reason: str) -> None:
        """Step ``i`` could not be delivered (failed, rejected, timed out): the run stops."""
        self._check_handed_out(i, "mark_failed")
        self._states[i] = "failed"
        if self.running:
            self.running = False
            self.outcome = "failed"
            self.reason = f"step {i + 1} ({self.script.steps[i].pattern}) failed: {reason}"

    def withdraw(self, i: int) -> None:
        """Step ``i`` was handed out but the run ended before it was sent: not sent."""
        self._check_handed_out(i, "withdraw")
        if self._states[i] == "sent" and not self._transmitted[i]:
            self._states[i], self._handed_at[i], self._next = "pending", None, min(self._next, i)

    def stop(self, reason: str = "stopped by the operator") -> None:
        """End the run; nothing more is handed out."""
        if self.running:
            self.running = False
            self.outcome = "stopped"
            self.reason = reason
