"""Which command the vehicle runs: the candidates with their probabilities and reasons.

* **Two-way link** (acknowledgements): the vehicle says what it runs, in its acknowledgements
  and the ``active`` command its status echoes; the newest of those decides, ``p`` is 1 for
  it and 0 for the commands that are not it (on their way, timed out, rejected), each with
  the reason in words.
* **One-way link**: nothing comes back (or only telemetry, whose status is then the last known
  state). Every command whose copies left since the last known state reached the vehicle with
  its record's ``p_delivered`` (the copies that actually left: a superseded command counts
  with those), and the newest that arrived is the one it runs
  (:func:`backend.belief.odds.running_odds`); the rest is the last known state, or unknown.

A record is the mission log's row (:meth:`backend.mission_log.store.MissionLog.command`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from backend.belief.model import BelievedCommand
from backend.belief.odds import running_odds

__all__ = ["Candidate", "Echo", "epoch_s", "one_way", "same_command", "two_way"]

Record = Mapping[str, Any]


@dataclass(frozen=True, slots=True)
class Echo:
    """The vehicle's own word on what it runs: ``command`` ``{pattern, params}`` (``params``
    None: not said, only the pattern), None: no command (it holds); ``at_s``: when it
    arrived (console clock, epoch s); ``what``: ``status`` or ``acknowledgement``."""

    command: Mapping[str, Any] | None
    at_s: float
    what: str


@dataclass(frozen=True, slots=True)
class Candidate:
    """One candidate: the belief as served, the record it is (None: not one of ours), when
    its first copy left (console clock, epoch s; None: not a record), and whether it is the
    last known state (what the vehicle did before any command sent since)."""

    belief: BelievedCommand
    record: Record | None = None
    sent_s: float | None = None
    last_known: bool = False


def epoch_s(iso: str | None) -> float | None:
    """An ISO 8601 stamp of the mission log as epoch seconds (None: none)."""
    if not iso:
        return None
    return datetime.fromisoformat(iso).timestamp()


def same_command(a: Mapping[str, Any] | None, b: Mapping[str, Any] | None) -> bool:
    """Both the same pattern and parameters (parameters not said: the pattern decides)."""
    if a is None or b is None or a.get("pattern") != b.get("pattern"):
        return False
    pa, pb = a.get("params"), b.get("params")
    return pa is None or pb is None or dict(pa) == dict(pb)


def percent_text(p: float) -> str:
    """``0.99951`` -> ``99.95 %``: enough decimals that a value below 1 never reads 100 %."""
    if p >= 1.0:
        return "100 %"
    for digits in range(2, 7):
        text = f"{100.0 * p:.{digits}f}"
        if float(text) < 100.0:
            return f"{float(text):g} %"
    return f"> {100.0 - 10.0**-6:.6f} %"


def _from_record(r: Record, p: float, reason: str) -> Candidate:
    belief = BelievedCommand(
        kind="command", id=r["id"], pattern=r["pattern"], params=r["params"], p=p, reason=reason
    )
    return Candidate(belief, r, epoch_s(r.get("first_sent_at")))


def _last_known(echo: Echo | None, p: float, reason: str, record: Record | None) -> Candidate:
    """The last known state as a candidate: the echo (one of our records when it matches)."""
    if echo is None:
        belief = BelievedCommand(
            kind="unknown", id=None, pattern=None, params=None, p=p, reason=reason
        )
        return Candidate(belief, last_known=True)
    cmd = echo.command
    if record is not None and cmd is not None:
        found = _from_record(record, p, reason)
        return Candidate(found.belief, record, found.sent_s, last_known=True)
    params = None if cmd is None or cmd.get("params") is None else dict(cmd["params"])
    pattern = None if cmd is None else cmd.get("pattern")
    belief = BelievedCommand(
        kind="last_known", id=None, pattern=pattern, params=params, p=p, reason=reason
    )
    return Candidate(belief, last_known=True)


def _echoed_record(records: Sequence[Record], echo: Echo, accepted: Record | None) -> Record | None:
    """The record the echo is: the last one the vehicle accepted if it matches, else the
    newest on the wire that matches."""
    if echo.command is None:
        return None
    if accepted is not None and same_command(echo.command, accepted):
        return accepted
    sent = [r for r in records if r.get("copies_sent")]
    return next((r for r in reversed(sent) if same_command(echo.command, r)), None)


def _echo_words(echo: Echo, now_s: float) -> str:
    cmd = echo.command
    what = "no active command (holding)" if cmd is None else f"{cmd.get('pattern')}"
    return f"the vehicle's last {echo.what} says it runs {what}"


def two_way(
    records: Sequence[Record], accepted: Record | None, echo: Echo | None, now_s: float
) -> list[Candidate]:
    """Two-way link: the candidates, the believed one (p 1) first, then those that are not
    it (p 0); ``records`` oldest first on the wire."""
    if echo is not None:
        record = _echoed_record(records, echo, accepted)
        words = _echo_words(echo, now_s)
        if record is not None:
            how = "acknowledged" if record["state"] == "acknowledged" else str(record["state"])
            words = f"{words}: command {record['id']} ({how})"
        elif echo.command is not None:
            words += ": not a command of this console (another station, or a restart?)"
        believed = _last_known(echo, 1.0, words, record)
    elif accepted is not None:
        found = _from_record(accepted, 1.0, "acknowledged by the vehicle (no echo since)")
        believed = Candidate(found.belief, accepted, found.sent_s, last_known=True)
    else:
        believed = _last_known(None, 1.0, "unknown: nothing heard from the vehicle yet", None)
    out = [believed]
    newest = believed.sent_s if believed.record is not None else None
    for r in reversed(records):  # newest first: the newest that is not the believed one
        sent = epoch_s(r.get("first_sent_at"))
        if believed.record is not None and r["id"] == believed.record["id"]:
            break
        if newest is not None and sent is not None and sent <= newest:
            break
        why = _NOT_IT.get(str(r["state"]))
        if why is not None:
            out.append(_from_record(r, 0.0, why))
            break
    return out


#: Why a command newer than the echoed one is not what the vehicle runs, by its state.
_NOT_IT = {
    "queued": "on its way: not acknowledged yet",
    "transmitted": "on its way: not acknowledged yet",
    "acknowledged": "acknowledged, but the vehicle's echo since is another",
    "rejected": "rejected by the vehicle",
    "timed_out": "timed out: no acknowledgement, and the vehicle's echo is another",
    "superseded": "superseded before an acknowledgement",
    "interrupted": "interrupted before an acknowledgement",
    "sent": "sent without an acknowledgement",
}


def one_way(
    records: Sequence[Record], echo: Echo | None, now_s: float, *, min_p: float = 0.0
) -> list[Candidate]:
    """One-way link: every command sent since the last known state (the echo's time, else
    every record given), with the probability that it is the one running, and the last known
    state with the rest; most probable first (``min_p``: candidates below it are left out)."""
    since = echo.at_s if echo is not None else -math.inf
    sent = [
        r
        for r in records
        if r.get("copies_sent") and (epoch_s(r.get("first_sent_at")) or -math.inf) > since
    ]
    odds, none = running_odds([float(r.get("p_delivered") or 0.0) for r in sent])
    out: list[Candidate] = []
    for k, (r, p) in enumerate(zip(sent, odds, strict=True)):
        n = int(r["copies_sent"])
        newer = len(sent) - k - 1
        reason = (
            f"one-way link: {n} cop{'y' if n == 1 else 'ies'} left, p(delivered) "
            f"{percent_text(float(r['p_delivered']))}"
        )
        if newer == 1:
            reason += "; the newer command did not arrive"
        elif newer:
            reason += f"; none of the {newer} newer commands arrived"
        out.append(_from_record(r, p, reason))
    n = len(sent)
    before = {0: "no command sent since", 1: "the command sent since did not arrive"}.get(
        n, f"none of the {n} commands sent since arrived"
    )
    if echo is not None:
        known = f"{before}: the last known state ({_echo_words(echo, now_s)})"
    else:
        known = f"{before}, and nothing is known of the vehicle before them (no telemetry)"
    echoed = _echoed_record(records, echo, None) if echo is not None else None
    out.append(_last_known(echo, none, known, echoed))
    out.sort(key=lambda c: c.belief.p, reverse=True)
    return [c for i, c in enumerate(out) if i == 0 or c.belief.p >= min_p]
