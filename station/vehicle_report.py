"""The rows of ``nemesys vehicle-check`` (:mod:`station.vehicle_check`): what each answer or
measurement means against the vehicle contract, and the report they make. No I/O."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final, Literal

from codec import (
    CODEWORD_BITS,
    GUARD_BITS,
    SYNC_WORD,
    CodecError,
    Encoded,
    Frame,
    RejectReason,
    encode_frame,
)
from station.link import capability_of
from station.vehicle_graph import GraphUnknown, VehicleGraph, verdict_of
from vehicle_contract.contract import (
    ACK_DEADLINE_S,
    CONTRACT_VERSION,
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_FRAME_ID,
    POSE_TOPIC,
    STATUS_TOPIC,
    TOPICS,
    topic,
)
from vehicle_contract.messages import pose_from_message
from vehicle_contract.payloads import validate_ack, validate_status

Result = Literal["pass", "fail", "skipped"]

#: A measured rate passes at this fraction of the contract's minimum.
RATE_TOLERANCE: Final = 0.95

#: The pre-dive probe: a deliberately malformed frame. Its preamble and delimiter are right, so
#: a receiver synchronises on it (over rosbridge or through an ME modem alike), but its codeword
#: is the all-zero codeword with 3 bits flipped (the first, the middle and the last): more
#: errors than BCH corrects (t = 2), and no codeword lies within 2 bits of it, so every
#: decoder rejects it as ``uncorrectable`` and, by the contract, acknowledges it and changes
#: nothing (tests/station/test_vehicle_report.py checks both).
PROBE_FRAME: Final = Frame(
    (SYNC_WORD << (CODEWORD_BITS + GUARD_BITS))
    | (((1 << (CODEWORD_BITS - 1)) | (1 << (CODEWORD_BITS // 2)) | 1) << GUARD_BITS)
)
#: The reason the probe's rejection must give.
PROBE_REASON: Final = RejectReason.UNCORRECTABLE.value
#: A pose that arrived longer ago than this is stale (s).
POSE_STALE_S: Final = 1.0


@dataclass(frozen=True)
class Check:
    """One row of the report."""

    name: str
    result: Result
    reason: str

    def as_json(self) -> dict[str, str]:
        return {"check": self.name, "result": self.result, "reason": self.reason}


@dataclass
class Report:
    """Every check against one vehicle."""

    url: str
    checks: list[Check]

    @property
    def failed(self) -> list[Check]:
        return [c for c in self.checks if c.result == "fail"]

    @property
    def ok(self) -> bool:
        return not self.failed

    def summary(self) -> str:
        counts = {r: sum(c.result == r for c in self.checks) for r in ("pass", "fail", "skipped")}
        tally = ", ".join(f"{n} {r}" for r, n in counts.items() if n)
        if self.ok:
            return f"PASS: {tally}"
        return f"FAIL: {tally} ({', '.join(c.name for c in self.failed)})"

    def as_json(self) -> dict[str, Any]:
        return {
            "url": self.url,
            "contract_version": CONTRACT_VERSION,
            "ok": self.ok,
            "summary": self.summary(),
            "checks": [c.as_json() for c in self.checks],
        }

    def table(self) -> str:
        width = max(len("check"), *(len(c.name) for c in self.checks))
        lines = [
            f"vehicle-check {self.url} (contract {CONTRACT_VERSION})",
            f"{'check':<{width}}  {'result':<7}  reason",
            f"{'-' * width}  {'-' * 7}  {'-' * 6}",
            *(f"{c.name:<{width}}  {c.result:<7}  {c.reason}" for c in self.checks),
            self.summary(),
        ]
        return "\n".join(lines)


@dataclass
class Ack:
    """An acknowledgement as it arrived: the object, or why there was none."""

    arrival_s: float
    ack: dict[str, Any] | None
    problem: str | None = None


def graph_checks(
    graph: VehicleGraph | GraphUnknown,
    *,
    modem: str | None = None,
    names: Mapping[str, str] | None = None,
) -> list[Check]:
    """The rosapi row, one row per contract topic and the onboard agent's, by the rule the
    console uses (:func:`station.vehicle_graph.verdict_of`: rosbridge's own node is not the
    vehicle). ``modem``: frames go through that ME modem, not the frame topic. ``names``:
    contract topic -> its name on this vehicle, for rows of a graph not known."""
    if isinstance(graph, GraphUnknown):
        unknown = f"not known: {graph}"
        named = names or {}
        return [
            Check("rosapi", "fail", str(graph)),
            *(
                Check(f"topic {named.get(t.name, t.name)}", "skipped", unknown)
                for t in TOPICS
                if t.required
            ),
            Check("onboard agent", "skipped", unknown),
        ]
    verdict = verdict_of(graph, frames_over_rosbridge=modem is None)
    out = [
        Check(
            "rosapi",
            "pass",
            f"{len(graph.topics)} topics listed; the contract topics' publishers and "
            "subscribers named",
        )
    ]
    for t in TOPICS:
        found = verdict.findings.get(t.name)  # an optional topic the graph lacks: no row
        row = f"topic {graph.name(t.name)}"
        if found is None:
            continue
        if found.ok:
            out.append(Check(row, "pass", found.reason))
        elif t.name == FRAME_TOPIC and modem is not None:
            why = f"frames go through the modem path ({modem}): {found.reason}"
            out.append(Check(row, "skipped", why))
        else:
            out.append(Check(row, "fail", f"missing: {found.reason}"))
    capability, _ = capability_of(graph, frames_over_rosbridge=modem is None)
    console = f"the console: {capability}"
    if verdict.agent:
        nodes = sorted({*graph.vehicle_nodes(MISSION_TOPIC), *graph.vehicle_nodes(STATUS_TOPIC)})
        said = f"{graph.name(MISSION_TOPIC)} and {graph.name(STATUS_TOPIC)}"
        why = f"running: {', '.join(nodes)} publishes {said}"
        out.append(Check("onboard agent", "pass", f"{why}; {console}"))
    else:
        out.append(Check("onboard agent", "fail", f"{verdict.problems[0]}; {console}"))
    return out


def malformed_probe_check(
    ack: Ack | None,
    *,
    sent_s: float,
    waited_s: float,
    path: str,
    active: object = None,
    deadline_s: float = ACK_DEADLINE_S,
) -> Check:
    """The probe's row: ``ack`` is the acknowledgement of :data:`PROBE_FRAME` (None: none came
    within ``waited_s`` of ``sent_s``); ``path`` says how it went; ``active`` is the active
    command the last status reported before it (``...``: not known). Its round trip is held to
    the contract's ack deadline (``deadline_s``; the round trip adds rosbridge's latency to
    the vehicle's own time, so a pass proves the deadline is kept); one past it fails, as does
    one the vehicle marks ``late`` (made after the deadline from the frame's reception)."""
    name = "ack path (probe)"
    what = f"a malformed frame ({PROBE_FRAME.hex}: codeword beyond correction) {path}"
    deadline = f"the contract's deadline {deadline_s:g} s"
    if ack is None:
        why = f"no acknowledgement within {waited_s:g} s ({deadline})"
        return Check(name, "fail", f"{what}: {why}")
    body = ack.ack or {}
    round_trip_s = ack.arrival_s - sent_s
    took = f"in {round_trip_s:.2f} s ({deadline})"
    if body.get("outcome") != "rejected":
        return Check(name, "fail", f"{what}: {body.get('outcome')} {took}: it must be rejected")
    if body.get("reason") != PROBE_REASON:
        why = f"rejected as {body.get('reason')!r}, not {PROBE_REASON!r}: {body.get('detail')}"
        return Check(name, "fail", f"{what}: {why}")
    if body.get("late") is True:
        why = "rejected, but late: the vehicle says it answered after the contract's deadline"
        return Check(name, "fail", f"{what}: {why}")
    if round_trip_s > deadline_s:
        why = f"rejected as {PROBE_REASON} {took}: the round trip is past the deadline"
        return Check(name, "fail", f"{what}: {why}")
    if active is not ... and "active" in body and body["active"] != active:
        why = f"the active command changed from {active} to {body['active']}"
        return Check(name, "fail", f"{what}: rejected, but {why}")
    return Check(name, "pass", f"{what}: rejected as {PROBE_REASON} {took}; nothing changed")


def probe_frame(active: object) -> tuple[Encoded | None, str | None]:
    """The frame that repeats the vehicle's reported active command exactly, or why there is
    none (a command whose values would snap would retask the vehicle, so it is not sent)."""
    if not isinstance(active, dict):
        return None, f"not an object: {active!r:.80}"
    pattern, params = active.get("pattern"), active.get("params")
    if not isinstance(pattern, str) or not isinstance(params, dict):
        return None, "no pattern name and params"
    try:
        enc = encode_frame(pattern, params)
    except (CodecError, TypeError, ValueError) as err:
        return None, str(err)
    if active.get("pattern_id", enc.command.pattern.id) != enc.command.pattern.id:
        return None, f"pattern_id {active.get('pattern_id')} is not {pattern}'s"
    changed = [str(s) for s in enc.snaps if s.changed]
    if changed:
        return None, "; ".join(changed)
    return enc, None


def rate_check(name: str, arrivals: list[float], minimum_hz: float, window_s: float) -> Check:
    n = len(arrivals)
    contract = f"contract: >= {minimum_hz:g} Hz"
    if n < 2:
        return Check(
            name, "fail", f"{n} message{'s' if n != 1 else ''} in {window_s:.1f} s ({contract})"
        )
    span_s = arrivals[-1] - arrivals[0]
    rate_hz = (n - 1) / span_s if span_s > 0 else math.inf
    result: Result = "pass" if rate_hz >= RATE_TOLERANCE * minimum_hz else "fail"
    return Check(name, result, f"{rate_hz:.1f} Hz ({n} messages over {span_s:.2f} s; {contract})")


def pose_checks(poses: list[tuple[float, float, dict[str, Any]]], window_s: float) -> list[Check]:
    minimum_hz = topic(POSE_TOPIC).rate_hz or 0.0
    checks = [rate_check("pose rate", [p[0] for p in poses], minimum_hz, window_s)]
    if not poses:
        return [*checks, *(Check(n, "skipped", "no pose") for n in ("pose frame_id", "pose age"))]
    ids = sorted({str(_header(msg).get("frame_id")) for _, _, msg in poses})
    wrong = [i for i in ids if i != POSE_FRAME_ID]
    if wrong:
        checks.append(Check("pose frame_id", "fail", f"{', '.join(wrong)}, not {POSE_FRAME_ID}"))
    else:
        checks.append(Check("pose frame_id", "pass", POSE_FRAME_ID))
    arrival_s, wall_s, msg = poses[-1]
    age_s = time.monotonic() - arrival_s
    stamp_s = pose_from_message(msg)["t_s"]
    offset = (
        "its stamp is unknown"
        if stamp_s is None
        else f"its stamp is {stamp_s - wall_s:+.3f} s from this computer's clock (information "
        "only: the vehicle keeps ROS time)"
    )
    result: Result = "pass" if age_s <= POSE_STALE_S else "fail"
    why = f"the last pose arrived {age_s:.2f} s ago (stale after {POSE_STALE_S:g} s); {offset}"
    checks.append(Check("pose age", result, why))
    return checks


def _header(msg: dict[str, Any]) -> dict[str, Any]:
    header = msg.get("header")
    return header if isinstance(header, dict) else {}


def status_checks(
    statuses: list[tuple[float, dict[str, Any] | None, str | None]], window_s: float
) -> list[Check]:
    minimum_hz = topic(STATUS_TOPIC).rate_hz or 0.0
    checks = [rate_check("status rate", [s[0] for s in statuses], minimum_hz, window_s)]
    if not statuses:
        return [*checks, Check("status schema", "skipped", "no status message to validate")]
    problems: list[str] = []
    bad = 0
    for _, body, problem in statuses:
        found = [problem] if problem is not None else validate_status(body)
        bad += bool(found)
        problems += [p for p in found if p not in problems]
    if bad:
        why = f"{bad} of {len(statuses)} invalid: {'; '.join(problems[:4])}"
        return [*checks, Check("status schema", "fail", why)]
    return [*checks, Check("status schema", "pass", f"{len(statuses)} valid")]


def ack_schema_check(acks: list[Ack]) -> Check:
    if not acks:
        return Check("ack schema", "skipped", "no acknowledgement to validate")
    problems: list[str] = []
    bad = 0
    for ack in acks:
        found = [ack.problem] if ack.problem is not None else validate_ack(ack.ack)
        bad += bool(found)
        problems += [p for p in found if p not in problems]
    if bad:
        return Check(
            "ack schema", "fail", f"{bad} of {len(acks)} invalid: {'; '.join(problems[:4])}"
        )
    return Check("ack schema", "pass", f"{len(acks)} valid")
