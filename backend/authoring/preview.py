"""What the console shows of a command before it is sent: the frame by section, and the plan
(path, estimates, limit checks, the change from the running plan). Pure functions of the
codec's and planner's results; :class:`backend.console.Console` adds the vehicle's state and
the link's odds."""

from __future__ import annotations

from typing import Any

from backend.authoring.durations import estimate_notes, flown
from backend.authoring.profile import VehicleProfile, battery_use_pct
from backend.chart.gps import Station
from backend.commands.checks import check_plan
from codec import FRAME_BITS, Encoded, airtime_s, sections
from onboard.agent import command_json
from planner import Limits, Plan, compare


def frame_doc(enc: Encoded, bitrate_bps: float) -> dict[str, Any]:
    """The frame: the command, the values asked for and sent, the bits by section, airtime (a
    fleet's addressed frame: its own sections and its 108 bits' airtime)."""
    cmd, frame = enc.command, enc.frame
    bits = frame.bits
    addressed = len(bits) != FRAME_BITS
    return {
        **command_json(cmd),
        "requested": {s.field: s.requested for s in enc.snaps},
        "snaps": [
            {
                "field": s.field,
                "requested": s.requested,
                "sent": s.sent,
                "unit": s.unit,
                "changed": s.changed,
                "text": str(s),
            }
            for s in enc.snaps
        ],
        "bits": bits,
        "hex": frame.hex,
        "sections": [
            {
                "name": sec.name,
                "start": sec.start,
                "length": sec.length,
                "bits": bits[sec.start : sec.start + sec.length],
            }
            for sec in sections(cmd.pattern, addressed=addressed)
        ],
        "airtime_ms": airtime_s(bitrate_bps, len(bits)) * 1e3,
        "bitrate_bps": bitrate_bps,
        "frame_bits": len(bits),  # 100, or a fleet's addressed 108
    }


def plan_doc(
    new: Plan,
    current: Plan | None,
    limits: Limits,
    profile: VehicleProfile | None = None,
    soc_pct: float | None = None,
    *,
    station: Station | None = None,
    range_m: float | None = None,
) -> dict[str, Any]:
    """The plan: path (NED, m; arrival times, s), estimates, the checks (every check's line
    and every violation, :func:`backend.commands.checks.check_plan`), diff from ``current``.

    With the vehicle's ``profile``, durations are as it flies the path (the kinematic twin,
    :mod:`backend.authoring.durations`; the planned ones beside them, and why they differ
    where they differ by more than 20 %), a speed above its top speed and a path longer
    than the battery lasts from ``soc_pct`` (None: full) are violations, and the checks its
    unknown figures prevent are listed; the battery use starts from ``soc_pct``. With the ME
    transmitter's ``station`` and the link's ``range_m``, a path leaving the range is a
    violation.
    """
    est, flight = flown(new, profile)
    path = new.path
    report = check_plan(
        new,
        limits=limits,
        profile=profile,
        soc_pct=soc_pct,
        station=station,
        range_m=range_m,
        estimate=est,
    )
    diff = None
    if current is not None:
        d = compare(current, new, estimates=(flown(current, profile)[0], est))
        diff = {
            "active": current.pattern,
            "changes": [
                {"param": c.param, "old": c.old, "new": c.new, "unit": c.unit} for c in d.changes
            ],
            "pattern_changed": d.pattern_changed,
            "duration_delta_s": d.delta("duration_s"),
            "length_delta_m": d.delta("length_m"),
            "anchor_moved_m": d.anchor_moved_m,
        }
    return {
        "path": {
            "x_m": list(path.xs),
            "y_m": list(path.ys),
            "z_m": list(path.zs),
            "t_s": list(path.times),
            "body_start": path.body_start,
            "repeats": path.loop_start is not None,
        },
        "estimate": {
            **{k: v for k, v in est.as_dict().items() if isinstance(v, int | float | None)},
            "join_length_m": est.transit_length_m,
            "join_duration_s": est.transit_duration_s,
            # a repeating pattern flies until retasked: its duration is the join and one lap,
            # never a total
            "repeats": est.repeats,
            # the whole battery fit, from the charge now, over the flyable duration
            "battery_pct": battery_use_pct(est.duration_s, soc_pct),
            "duration_notes": estimate_notes(new, est, flight, profile),
        },
        "violations": [v.as_json() for v in report.violations],
        "checks": [
            {"check": line.check, "status": line.status, "detail": line.detail}
            for line in report.lines
        ],
        "skipped_checks": profile.skipped_checks() if profile is not None else [],
        "diff": diff,
    }
