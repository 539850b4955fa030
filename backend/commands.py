"""Command lifecycle: queued -> transmitted -> acknowledged | rejected | timed_out | failed.

Every command is written to the mission log (state ``queued``) before anything is transmitted,
and every change of state is written before it is announced. Acknowledgements from the vehicle
are matched to the command they answer by the received frame (exact, then within the BCH
correction radius, then the oldest awaiting one: :func:`sim_bridge.transmit.ack_match`).

Surface (the abort) is never rate limited and is sent again every ``surface_repeat_s`` until
the vehicle acknowledges it. The console keeps a mirror of the vehicle's plan: on every
accepted acknowledgement it replans from the state the vehicle reports it planned from, so its
previews join from exactly the plan the vehicle flies.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from typing import Any

from backend.link import Link
from backend.store import MissionLog, now_iso
from backend.telemetry import TelemetryHub
from codec import Encoded, decode_frame, encode_frame
from planner import Plan, PlanError, VehicleState, plan
from sim_bridge.agent import command_json
from sim_bridge.transmit import ack_match

logger = logging.getLogger("backend.commands")


class RateLimited(Exception):
    """Too many transmissions; ``retry_after_s`` until the next is allowed."""

    def __init__(self, retry_after_s: float, limit: int) -> None:
        super().__init__(
            f"at most {limit} transmissions a minute; try again in {retry_after_s:.0f} s "
            "(Surface is never limited)"
        )
        self.retry_after_s = retry_after_s


class NotRetryable(Exception):
    """The command cannot be retried in its state."""


class CommandManager:
    """Owns transmissions, acknowledgements, timeouts and the vehicle's plan mirror."""

    def __init__(
        self,
        log: MissionLog,
        link: Link,
        hub: TelemetryHub,
        *,
        dive: Callable[[], int],
        operator: str,
        ack_timeout_s: float,
        surface_repeat_s: float,
        max_sends_per_minute: int,
        link_delay_s: Callable[[], float] = lambda: 0.0,
        airtime_s: float = 100 / 36000,
        target: str | None = None,
    ) -> None:
        self.log = log
        self.link = link
        #: What the log records as the target (the settings' name for it, e.g. "sim").
        self.target = target or link.target
        self.hub = hub
        self._dive = dive
        self.operator = operator
        self.ack_timeout_s = ack_timeout_s
        self.surface_repeat_s = surface_repeat_s
        self.max_sends_per_minute = max_sends_per_minute
        self._link_delay_s = link_delay_s
        self.airtime_s = airtime_s
        self._sends: deque[float] = deque()
        self._awaiting: OrderedDict[int, Encoded] = OrderedDict()  # id -> frame, oldest first
        self._timeouts: dict[int, asyncio.TimerHandle] = {}
        self._surface_task: asyncio.Task[None] | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        self.mirror: Plan | None = None  # the vehicle's plan, as replayed here
        self.vehicle_active: dict[str, Any] | None = None  # the vehicle's echoed command
        self.last_sent: dict[str, Any] | None = None
        #: The newest command (by id) the vehicle accepted from this console: its record.
        self._accepted: dict[str, Any] | None = None
        self.on_plan: Callable[[Plan], None] = lambda _p: None

    async def close(self) -> None:
        for handle in self._timeouts.values():
            handle.cancel()
        tasks = list(self._tasks)
        if self._surface_task is not None:
            tasks.append(self._surface_task)
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task

    def reset_vehicle(self) -> None:
        """The vehicle started afresh (training reset): forget its plan and echoes."""
        self.mirror = None
        self.vehicle_active = None
        self._accepted = None
        for handle in self._timeouts.values():
            handle.cancel()
        self._timeouts.clear()
        for cid in list(self._awaiting):
            self._update(cid, state="timed_out", reason="the vehicle was reset")
        self._awaiting.clear()

    # --- sending -------------------------------------------------------------------------

    def _check_rate(self) -> None:
        now = time.monotonic()
        while self._sends and now - self._sends[0] > 60.0:
            self._sends.popleft()
        if len(self._sends) >= self.max_sends_per_minute:
            raise RateLimited(60.0 - (now - self._sends[0]), self.max_sends_per_minute)

    async def submit(self, enc: Encoded, kind: str = "command") -> dict[str, Any]:
        """Log the command (queued) with the values asked for (``enc.snaps``), then transmit
        it in the background; returns the record.

        Raises:
            RateLimited: too many transmissions in the last minute (never for surface).
        """
        if kind != "surface":
            self._check_rate()
            self._sends.append(time.monotonic())
        record = self.log.insert_command(
            self._dive(),
            {
                "operator": self.operator,
                "target": self.target,
                "kind": kind,
                **command_json(enc.command),
                "requested": {s.field: s.requested for s in enc.snaps},
                "bits": enc.frame.bits,
                "hex": enc.frame.hex,
            },
        )
        self._announce(record)
        if kind == "surface":
            if self._surface_task is not None:
                self._surface_task.cancel()
            self._surface_task = asyncio.create_task(self._surface_loop(record["id"], enc))
        else:
            self._spawn(self._transmit(record["id"], enc))
        return record

    async def surface(self) -> dict[str, Any]:
        return await self.submit(encode_frame("surface", {}), kind="surface")

    def retry(self, command_id: int) -> dict[str, Any]:
        record = self.log.command(command_id)
        if record is None:
            raise KeyError(command_id)
        if record["state"] not in ("timed_out", "failed", "rejected"):
            raise NotRetryable(
                f"command {command_id} is {record['state']}; only timed_out, failed or "
                "rejected commands can be retried"
            )
        self._check_rate()
        self._sends.append(time.monotonic())
        enc = encode_frame(record["pattern"], record["params"])
        self._spawn(self._transmit(command_id, enc))
        return record

    def _spawn(self, coro: Any) -> None:
        task = asyncio.create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _transmit(self, command_id: int, enc: Encoded) -> None:
        record = self.log.command(command_id)
        attempts = (record or {}).get("attempts", 0) + 1
        reason = await self.link.transmit(enc.frame)
        if reason is not None:
            self._update(command_id, state="failed", attempts=attempts, reason=reason)
            return
        self.last_sent = {"id": command_id, **command_json(enc.command)}
        now = self.log.command(command_id)
        if now is not None and now["state"] == "acknowledged":
            # an earlier attempt was acknowledged while this one was on its way (a Surface
            # repeat): count the attempt, keep the acknowledgement
            self._update(command_id, attempts=attempts)
            return
        self._update(
            command_id, state="transmitted", attempts=attempts, sent_at=now_iso(), reason=None
        )
        if not self.link.acknowledges:
            return
        self._awaiting[command_id] = enc
        self._awaiting.move_to_end(command_id)
        old = self._timeouts.pop(command_id, None)
        if old is not None:
            old.cancel()
        wait = self.ack_timeout_s + self.airtime_s + self._link_delay_s()
        loop = asyncio.get_running_loop()
        self._timeouts[command_id] = loop.call_later(wait, self._timed_out, command_id)

    async def _surface_loop(self, command_id: int, enc: Encoded) -> None:
        while True:
            await self._transmit(command_id, enc)
            await asyncio.sleep(self.surface_repeat_s)
            record = self.log.command(command_id)
            if record is None or record["state"] == "acknowledged":
                return

    def _timed_out(self, command_id: int) -> None:
        self._timeouts.pop(command_id, None)
        if self._awaiting.pop(command_id, None) is not None:
            self._update(command_id, state="timed_out", reason="no acknowledgement in time")

    def _update(self, command_id: int, **fields: Any) -> dict[str, Any]:
        record = self.log.update_command(command_id, **fields)
        self._announce(record)
        return record

    def _announce(self, record: dict[str, Any]) -> None:
        self.hub.publish({"type": "command", "command": record})

    # --- acknowledgements ----------------------------------------------------------------

    def on_mission(self, ack: dict[str, Any]) -> None:
        """An acknowledgement from the vehicle: settle the command it answers."""
        self.vehicle_active = ack.get("active")
        command_id = self._match(ack)
        if command_id is not None:
            self._awaiting.pop(command_id, None)
            handle = self._timeouts.pop(command_id, None)
            if handle is not None:
                handle.cancel()
            accepted = ack.get("outcome") == "accepted"
            record = self._update(
                command_id,
                state="acknowledged" if accepted else "rejected",
                acked_at=now_iso(),
                ack=ack,
                reason=None if accepted else f"{ack.get('reason')}: {ack.get('detail')}",
            )
            newest = self._accepted is None or command_id > self._accepted["id"]
            if accepted and newest:
                self._accepted = record
        if ack.get("outcome") == "accepted" and not ack.get("duplicate") and ack.get("from"):
            self._replay_plan(ack)
        self.hub.publish(
            {"type": "vehicle", "active": self.vehicle_active, "echo_mismatch": self.echo_mismatch}
        )

    def _match(self, ack: dict[str, Any]) -> int | None:
        if not self._awaiting:
            return None
        best: tuple[int, int] | None = None  # (rank, id): exact 0, near 1
        for cid, enc in self._awaiting.items():
            how = ack_match(enc.frame, ack)
            rank = {"exact": 0, "near": 1}.get(how or "", 2)
            if best is None or rank < best[0]:
                best = (rank, cid)
        return best[1] if best is not None else None

    def _replay_plan(self, ack: dict[str, Any]) -> None:
        try:
            cmd = decode_frame(
                encode_frame(ack["command"]["pattern"], ack["command"]["params"]).frame.bits
            ).command
            state = VehicleState(**ack["from"])
            self.mirror = plan(cmd, state, self.mirror)
        except (PlanError, KeyError, TypeError, ValueError) as err:
            logger.warning("cannot mirror the vehicle's plan: %s", err)
            return
        self.on_plan(self.mirror)

    @property
    def echo_mismatch(self) -> bool:
        """The vehicle's echo of its active command (the last acknowledgement's ``active``,
        and the pattern in its status) differs from the last command it accepted from this
        console (in this dive): retasked by someone else, restarted, or a console bug."""
        last = self._accepted
        if last is None or last["dive"] != self._dive():
            return False
        status = self.hub.status or {}
        acked_t_s = (last.get("ack") or {}).get("t_s", 0.0)
        # a status from before the acknowledgement still shows the old pattern: not a mismatch
        if status.get("t_s", 0.0) > acked_t_s and status.get("pattern") != last["pattern"]:
            return True
        active = self.vehicle_active
        if active is None:
            return False
        return (active.get("pattern"), active.get("params")) != (last["pattern"], last["params"])
