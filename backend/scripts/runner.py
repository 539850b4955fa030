"""Mission scripts, run: the state machine the console drives while a script runs.

A step "on completion" goes when the previous step completes, and the run is over when its
last step completes, read the same way (:mod:`backend.scripts.completion`): as the vehicle
reports it where its status reaches the console, else by the estimate (the step's estimated
completion after it was handed out, said to be estimated). A repeating last step leaves the
vehicle "running until retasked".
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal

from backend.scripts.completion import after_repeating, vehicle_verdict
from backend.scripts.expand import ExpandedStep, expand
from backend.scripts.labels import describe_steps, run_summary
from backend.scripts.model import MissionScript, RunMode, StepState, WaitingFor
from codec import decode_frame, encode_frame
from planner import VehicleState

Outcome = Literal["running", "completed", "until_retasked", "stopped", "failed"]
#: How the run knows a step completed: the vehicle's status, or the estimate (a link that
#: reports nothing).
CompletionBy = Literal["vehicle", "estimate"]

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
      the constructor's, else the first poll's ``now_s``); ``after_previous`` steps when step
      ``i - 1`` completes (below); ``operator`` steps are proposed and wait for :meth:`go`;
    * ``mode="step"``: every step is proposed and waits for :meth:`go`;
    * :meth:`mark_failed` and :meth:`stop` end the run;
    * the step whose completion the run waits for (the one before an ``after_previous`` step
      in auto mode, or the last), once acknowledged, completes: with
      ``completion_by="vehicle"`` when a status fed to :meth:`observe` says so (a status
      saying it will not complete, a retask or an empty battery, stops the run); with
      ``"estimate"`` (a link that reports nothing) ``completion_s`` after it was handed out,
      by :meth:`poll`. The last step's completion ends the run; a repeating last step ends it
      once acknowledged, the vehicle ``until_retasked``.

    A handed-out step shows as ``sent`` (``transmitted`` false until :meth:`mark_sent`).

    Args:
        script: a validated script.
        mode: ``auto`` or ``step``.
        completion_s: each step's estimated completion (s after it takes effect; ``None``:
            it repeats), from the expansion the run was planned with
            (:meth:`ScriptRunner.planned` gives them). Default: the script expanded from the
            NED origin at the surface, at rest, by a vehicle of unknown figures.
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
        start_s: float | None = None,
        clock: Callable[[], float] | None = None,
        completion_by: CompletionBy = "estimate",
        vehicle: str | None = None,
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
        self.completion_by: CompletionBy = completion_by
        #: The fleet's vehicle the run drives (every step names it); None without a fleet.
        self.vehicle = vehicle
        self.now_s: float | None = None
        self.running = True
        self.outcome: Outcome = "running"
        self.reason: str | None = None
        #: Which steps completed, and when (run clock, as the vehicle reported or estimated):
        #: the steps the run waited for only (the last: the run's completion).
        self._done = [False] * n
        self._done_at: list[float | None] = [None] * n
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
        completion_by: CompletionBy = "estimate",
        vehicle: str | None = None,
    ) -> ScriptRunner:
        """A runner timed by ``expanded`` (:func:`backend.scripts.expand.expand` of
        ``script`` from where the vehicle is, timed by its profile), as the preview is."""
        return cls(
            script,
            mode,
            completion_s=[s.completion_s for s in expanded],
            clock=clock,
            completion_by=completion_by,
            vehicle=vehicle,
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

    def watched(self) -> int | None:
        """The step whose completion the run waits for now: before an ``after_previous`` step
        in auto mode, or the last once every step is handed out; acknowledged, not yet
        complete. ``None``: none."""
        if not self.running or not self._previous_acknowledged():
            return None
        i = self.next_index
        if i is None:
            return len(self._states) - 1
        after = self.script.steps[i].trigger.kind == "after_previous"
        waits = i > 0 and after and self.mode == "auto" and not self._done[i - 1]
        return i - 1 if waits else None

    def expected_s(self, i: int) -> float | None:
        """When step ``i`` is estimated to complete (run clock): its estimated completion
        after it was handed out; ``None``: unknown, or it repeats."""
        handed, takes = self._handed_at[i], self.completion_s[i]
        return None if handed is None or takes is None else handed + takes

    def due_s(self) -> float | None:
        """For an ``at`` or ``after_previous`` step in auto mode: when it is due (run clock),
        if known (acknowledgement of the previous step still needed; on completion: when the
        vehicle reported the previous step complete, else its estimated completion); once
        every step is handed out, when the last one is expected to complete (estimated)."""
        i = self.next_index
        if i is None:
            return self.expected_s(len(self._states) - 1)
        if self.mode != "auto" or self.start_s is None:
            return None
        t = self.script.steps[i].trigger
        if t.kind == "at" and t.t_s is not None:
            return self.start_s + t.t_s
        if t.kind == "after_previous" and i > 0:
            if self._done[i - 1]:
                return self._done_at[i - 1] if self._done_at[i - 1] is not None else self.now_s
            return self.expected_s(i - 1) if self.completion_by == "estimate" else None
        return None

    def _rel(self, t: float | None) -> float | None:
        """A run-clock value as seconds from the run's start."""
        return None if t is None or self.start_s is None else round(t - self.start_s, 3)

    def state(self) -> dict[str, Any]:
        """The run as JSON (:class:`backend.api.schemas.RunState`); times in s from the run's
        start, the texts in words (:mod:`backend.scripts.labels`)."""
        proposed, watched = self.proposed(), self.watched()
        # a fleet's run names its vehicle in every step (the run's log says where each went)
        named = {} if self.vehicle is None else {"vehicle": self.vehicle}
        nxt: dict[str, Any] | None = None
        if proposed is not None:
            s = self.script.steps[proposed]
            nxt = {
                "index": proposed,
                "pattern": s.pattern,
                "params": dict(s.params),
                "trigger": s.trigger.model_dump(),
                **named,
            }
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
                "completed_s": self._rel(self._done_at[i]),
                **named,
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
            "expected_s": self._rel(self.expected_s(watched)) if watched is not None else None,
            "elapsed_s": self._rel(self.now_s),
            "completion_by": self.completion_by,
            "completed_s": self._rel(self._done_at[-1]),
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
        With ``completion_by="estimate"`` the step the run waits for completes at its
        estimated completion (the last: the run ends)."""
        now = self._now(now_s)
        if self.start_s is None:
            self.start_s = now
        self.now_s = now
        w = self.watched()
        if w is not None and self.completion_by == "estimate":
            expected = self.expected_s(w)
            if expected is not None and now >= expected - EPS_S:
                self._step_complete(w, expected)
        i = self.next_index
        if not self.running or i is None or not self._previous_acknowledged():
            return []
        due = self.due_s()  # None in step mode
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
        self._states[i], self._handed_at[i], self._next = "sent", now, i + 1

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
        if self.running and every and self.completion_s[-1] is None:
            # the last step repeats: nothing more to wait for
            self.running, self.outcome = False, "until_retasked"

    def observe(self, status: Mapping[str, Any] | None) -> None:
        """The vehicle's latest status (``completion_by="vehicle"``): the step the run waits
        for (:meth:`watched`) completes when it reports that step complete (the last: the run
        is over); the run stops when it reports that step will not complete (retasked,
        battery empty)."""
        w = self.watched()
        if w is None or self.completion_by != "vehicle":
            return
        command = self._commands[w]
        verdict, why = vehicle_verdict(
            status, command.pattern.name, command.params, self._acked_t_s[w]
        )
        if verdict == "complete":
            self._step_complete(w, self.clock() if self.clock is not None else self.now_s)
        elif verdict == "ended":
            self.stop(f"step {w + 1} ({self.script.steps[w].pattern}) will not complete: {why}")

    def _step_complete(self, i: int, at: float | None) -> None:
        self._done[i], self._done_at[i] = True, at
        if i == len(self._states) - 1:
            self.running, self.outcome = False, "completed"

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
