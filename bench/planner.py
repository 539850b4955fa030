"""``nemesys bench planner``: replan latency per pattern and the onboard memory footprint.

Latency: the paper's "replan latency", time from a decoded command to the full path and its
first setpoint (``plan()`` then ``path.sample(0)``), for every pattern at its default
parameters, retasking a vehicle that is flying the default square (so every case includes the
join). Shown in total and normalised per waypoint, beside the paper's figures (15-46 ms per
waypoint; 26 ms for a 4-waypoint square, 1.62 s for a 36-waypoint circle). All patterns run
interleaved in one process; medians of the rounds are printed.

Memory: peak RSS (``VmHWM``) of a fresh interpreter that imports the onboard path
(``codec``, ``planner``), decodes one frame per pattern and replans each in turn, against a
plain interpreter started the same way (``python -I -S``: no ``site``, so no start-up hook
preloads modules into the baseline; the checkout's root alone on ``sys.path``), medians of
several runs, with the packages' bytecode compiled first as on an installed vehicle. The
frames carry 0, 1 and 2 codeword bit errors in turn, so the error correction's memory is
counted; the process prints the bits it corrected and the bench checks them. The kernel counts
in KiB ("kB"); figures are printed in MiB. The paper reports 13.2 "MB" for its
decode-and-replan process.
"""

from __future__ import annotations

import random
import statistics
from typing import TextIO

from bench._onboard import ERROR_COUNTS, with_errors
from bench._timing import compile_packages, interleaved_medians, mib, peak_rss_run, table
from codec import DICTIONARY, Command, decode_frame, encode_frame
from planner import Plan, VehicleState, plan

TARGET_TOTAL_US = 200.0
TARGET_PER_WAYPOINT_US = 5.0
TARGET_EXTRA_RSS_KB = 1024
PAPER_PER_WAYPOINT_MS = (15.0, 46.0)
PAPER_SQUARE_MS, PAPER_SQUARE_WAYPOINTS = 26.0, 4
PAPER_CIRCLE_MS, PAPER_CIRCLE_WAYPOINTS = 1620.0, 36
PAPER_RSS_MB = 13.2

# Peak RSS of this process (KiB): VmHWM belongs to the address space exec created, whereas
# ru_maxrss also counts the parent's pages the child had between fork and exec.
_PEAK = "print(open('/proc/self/status').read().split('VmHWM:')[1].split()[0])"
_BARE = _PEAK
_ONBOARD = (
    """
import sys
from codec import decode_frame
from planner import VehicleState, plan
state = VehicleState(3.0, 4.0, 5.0, 90.0, 0.5)
current = None
corrected = []
for frame in sys.argv[1:]:
    decoded = decode_frame(frame)
    corrected.append(decoded.corrected)
    current = plan(decoded.command, state, current)
    current.path.sample(0.0)
print(*corrected)
"""
    + _PEAK
)


def default_commands() -> dict[str, Command]:
    """Every pattern at its defaults, as the vehicle decodes it."""
    return {
        name: decode_frame(encode_frame(name, p.defaults).frame.bits).command
        for name, p in DICTIONARY.items()
    }


def running_square() -> tuple[Plan, VehicleState]:
    """A vehicle 30 s into the default square, and that plan."""
    square = default_commands()["square"]
    first = plan(square, VehicleState(0.0, 0.0, 5.0, 0.0, 0.5))
    sp = first.path.sample(30.0)
    state = VehicleState(sp.x_m, sp.y_m, sp.z_m, sp.course_deg, sp.speed_mps, 30.0)
    return first, state


def compile_onboard() -> None:
    """Write the onboard packages' bytecode, as installing them on the vehicle does (even
    under PYTHONDONTWRITEBYTECODE): compiling source costs a fresh process ~1.5 MB of peak
    RSS that an installed vehicle never pays."""
    compile_packages(("codec", "planner"))


def onboard_frames(seed: int = 15) -> tuple[list[str], tuple[int, ...]]:
    """One frame per pattern at its defaults (hex), with 0, 1, 2, 0, ... codeword bit errors;
    and those error counts."""
    rng = random.Random(seed)
    frames, errors = [], []
    for i, (name, p) in enumerate(DICTIONARY.items()):
        n = ERROR_COUNTS[i % len(ERROR_COUNTS)]
        value = with_errors(encode_frame(name, p.defaults).frame.value, n, rng)
        frames.append(format(value, "025x"))
        errors.append(n)
    return frames, tuple(errors)


def memory_kb(runs: int) -> tuple[int, int, tuple[int, ...]]:
    """Median peak RSS (KiB) of the plain interpreter and of the onboard decode + replan of
    frames with bit errors, interleaved; and the bits the onboard process corrected per frame.

    Raises:
        RuntimeError: the process did not correct exactly the errors put in the frames.
    """
    compile_onboard()
    frames, errors = onboard_frames()
    bare: list[int] = []
    onboard: list[int] = []
    corrected: tuple[int, ...] = ()
    for _ in range(runs):
        bare.append(peak_rss_run(_BARE, frames)[0])
        peak, printed = peak_rss_run(_ONBOARD, frames)
        onboard.append(peak)
        corrected = tuple(int(c) for c in printed[-1].split())
        if corrected != errors:
            raise RuntimeError(f"the onboard process corrected {corrected}, expected {errors}")
    return int(statistics.median(bare)), int(statistics.median(onboard)), corrected


def _verdict(ok: bool) -> str:
    return "met" if ok else "MISSED"


def run(out: TextIO, quick: bool = False) -> int:
    commands = default_commands()
    current, state = running_square()
    sizes = {name: len(plan(cmd, state, current).path) for name, cmd in commands.items()}

    def replan(cmd: Command) -> object:
        return plan(cmd, state, current).path.sample(0.0)

    loops = 20 if quick else 200
    cases = {name: (replan, [cmd], loops) for name, cmd in commands.items()}
    medians = interleaved_medians(cases, rounds=5 if quick else 15)
    rows = []
    for name, us in medians.items():
        per = us / sizes[name]
        rows.append(
            [
                name,
                str(sizes[name]),
                f"{us:.1f}",
                f"{per:.2f}",
                f"<= {TARGET_TOTAL_US:.0f} {_verdict(us <= TARGET_TOTAL_US)}",
                f"<= {TARGET_PER_WAYPOINT_US:.0f} {_verdict(per <= TARGET_PER_WAYPOINT_US)}",
                f"{PAPER_PER_WAYPOINT_MS[0]:.0f}-{PAPER_PER_WAYPOINT_MS[1]:.0f} ms",
            ]
        )
    out.write(
        "Replan latency: decoded command -> full path + first setpoint, default parameters,\n"
        "retasking a vehicle 30 s into the default square (median of interleaved rounds)\n\n"
    )
    headers = [
        "pattern",
        "waypoints",
        "total us",
        "us/waypoint",
        "target total us",
        "target us/wp",
        "paper /wp",
    ]
    out.write(table(headers, rows) + "\n\n")
    sq, ci = medians["square"], medians["circle"]
    worst_per = max(medians[n] / sizes[n] for n in medians)
    paper_rows = [
        [
            f"square ({PAPER_SQUARE_WAYPOINTS} wp in the paper, {sizes['square']} here)",
            f"{PAPER_SQUARE_MS:g} ms",
            f"{sq / 1e3:.3f} ms",
            f"{PAPER_SQUARE_MS * 1e3 / sq:,.0f}x faster",
        ],
        [
            f"circle ({PAPER_CIRCLE_WAYPOINTS} wp in the paper, {sizes['circle']} here)",
            f"{PAPER_CIRCLE_MS:g} ms",
            f"{ci / 1e3:.3f} ms",
            f"{PAPER_CIRCLE_MS * 1e3 / ci:,.0f}x faster",
        ],
        [
            "normalised, best paper vs our worst",
            f"{PAPER_PER_WAYPOINT_MS[0]:g} ms/wp",
            f"{worst_per / 1e3:.4f} ms/wp",
            f"{PAPER_PER_WAYPOINT_MS[0] * 1e3 / worst_per:,.0f}x faster",
        ],
    ]
    out.write(table(["against the paper", "paper", "ours", "ratio"], paper_rows) + "\n\n")
    runs = 3 if quick else 7
    bare, onboard, corrected = memory_kb(runs)
    extra = onboard - bare
    mem_rows = [
        ["plain interpreter (python -I -S, the baseline)", mib(bare), "", ""],
        [
            f"import codec + planner, decode {len(corrected)} frames, replan each",
            mib(onboard),
            f'paper {PAPER_RSS_MB} "MB"',
            "",
        ],
        [
            "added by the onboard path",
            mib(extra),
            f"<= {mib(TARGET_EXTRA_RSS_KB)}",
            _verdict(extra <= TARGET_EXTRA_RSS_KB),
        ],
    ]
    out.write(
        f"Peak RSS (VmHWM, KiB shown as MiB), median of {runs} fresh processes each; the frames "
        f"carry codeword bit errors, corrected: {' '.join(map(str, corrected))}\n\n"
    )
    out.write(table(["process", "peak RSS", "target / paper", ""], mem_rows) + "\n")
    return 0
