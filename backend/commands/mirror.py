"""The console's mirror of the vehicle: the plan it flies and the command it echoes.

On every accepted acknowledgement the console replans from the state the vehicle reports it
planned from, so its previews join from exactly the plan the vehicle flies. The echo check
compares what the vehicle says it runs with the last command it accepted from this console.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

from backend.telemetry import TelemetryHub
from codec import decode_frame, encode_frame
from planner import Plan, PlanError, VehicleState, plan
from vehicle_contract.messages import number

logger = logging.getLogger("backend.commands.mirror")


class VehicleMirror:
    """The vehicle's plan as replayed here, its echoed command and the echo check."""

    def __init__(self, hub: TelemetryHub, dive: Callable[[], int]) -> None:
        self.hub = hub
        self._dive = dive
        self.plan: Plan | None = None
        #: The vehicle's echo of its active command (the last acknowledgement's ``active``).
        self.active: dict[str, Any] | None = None
        #: The newest command (by id) the vehicle accepted from this console: its record.
        self.accepted: dict[str, Any] | None = None
        #: When the last acknowledgement arrived (monotonic s); the state the vehicle planned
        #: from in the last one it accepted, with when it arrived (a fix, for the belief).
        self.heard_s: float | None = None
        self.planned_from: tuple[float, dict[str, Any]] | None = None
        self.on_plan: Callable[[Plan], None] = lambda _p: None

    def reset(self) -> None:
        """The vehicle started afresh (training reset): forget its plan and echoes."""
        self.plan = None
        self.active = None
        self.accepted = None
        self.heard_s = None
        self.planned_from = None

    def on_ack(self, ack: dict[str, Any], record: dict[str, Any] | None) -> None:
        """An acknowledgement, with the record it settled (if it matched one)."""
        self.active = ack.get("active")
        self.heard_s = time.monotonic()
        accepted = ack.get("outcome") == "accepted"
        newest = record is not None and (
            self.accepted is None or record["id"] > self.accepted["id"]
        )
        if accepted and newest:
            self.accepted = record
        if accepted and not ack.get("duplicate") and ack.get("from"):
            self.planned_from = (self.heard_s, ack["from"])
            self._replay_plan(ack)

    def _replay_plan(self, ack: dict[str, Any]) -> None:
        try:
            cmd = decode_frame(
                encode_frame(ack["command"]["pattern"], ack["command"]["params"]).frame.bits
            ).command
            state = VehicleState(**ack["from"])
            self.plan = plan(cmd, state, self.plan)
        except (PlanError, KeyError, TypeError, ValueError) as err:
            logger.warning("cannot mirror the vehicle's plan: %s", err)
            return
        self.on_plan(self.plan)

    @property
    def echo_mismatch(self) -> bool:
        """The vehicle's echo of its active command (the last acknowledgement's ``active``,
        and the pattern in its status) differs from the last command it accepted from this
        console (in this dive): retasked by someone else, restarted, or a console bug."""
        last = self.accepted
        if last is None or last["dive"] != self._dive():
            return False
        status = self.hub.status or {}
        acked_t_s = number((last.get("ack") or {}).get("t_s")) or 0.0
        status_t_s = number(status.get("t_s"))
        # a status from before the acknowledgement still shows the old pattern: not a mismatch
        fresh = status_t_s is not None and status_t_s > acked_t_s
        if fresh and status.get("pattern") != last["pattern"]:
            return True
        active = self.active
        if active is None:
            return False
        return (active.get("pattern"), active.get("params")) != (last["pattern"], last["params"])

    def mismatch_event(self) -> tuple[str, dict[str, Any]]:
        """An echo mismatch as the mission log keeps it: (detail in words, data)."""
        last = self.accepted or {}
        active = self.active or {"pattern": (self.hub.status or {}).get("pattern")}
        detail = (
            f"the vehicle runs {active.get('pattern')}, not {last.get('pattern')} (command "
            f"{last.get('id')}, the last it accepted from this console): retasked by another "
            "station, restarted, or not this console's vehicle"
        )
        return detail, {"vehicle_active": active, "last_accepted_id": last.get("id")}
