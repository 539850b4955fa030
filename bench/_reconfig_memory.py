"""The memory half of ``nemesys bench reconfig``: peak RSS of a fresh interpreter running the
onboard decode + replan of the three retask scenarios, against a plain interpreter.

The onboard process imports the onboard path (``codec``, ``planner``, the agent and
guidance), builds an agent per scenario and feeds it the scenario's first frame and then its
retask frame, from the vehicle states the scenario's acknowledgments record. The frames carry
the codeword bit errors of :data:`MEMORY_ERRORS`, so the error correction's memory is part of
what is measured; the process prints the bits the agent corrected and :func:`measure_memory`
checks them. The kernel counts in KiB ("kB"); the report prints MiB.

Both processes are plain interpreters (:data:`bench._timing.PLAIN_BASELINE`: ``python -I -S``
with the checkout's root alone on ``sys.path``), so the increment counts every module the
onboard path loads, the standard library's included, and nothing a start-up hook preloaded
into the baseline; the onboard packages' bytecode is compiled first for the interpreter
measured (:func:`compile_onboard`), as installing them on a vehicle does, and so is the
onboard process's own driver (imported as a module, as a vehicle's node is, rather than
compiled from ``-c`` source).
"""

from __future__ import annotations

import random
import statistics
import tempfile
from pathlib import Path

from bench._onboard import with_errors
from bench._timing import compile_packages, peak_rss_run
from sim.scenarios import SCENARIOS, run_scenario

#: The retask scenarios, in the paper's order.
RETASK_SCENARIOS = ("wreck", "panel", "pod")

#: The vehicle's packages: all the onboard process may load of the checkout.
ONBOARD_PACKAGES = ("codec", "planner", "onboard", "vehicle_contract")
#: The onboard path's bound on the increment over a plain interpreter (KiB: 1.0 MiB).
TARGET_INCREMENT_KB = 1024
#: Codeword bit errors put in each scenario's (first, retask) frame for the memory run.
MEMORY_ERRORS = {"wreck": (1, 2), "panel": (2, 0), "pod": (2, 1)}

# Peak RSS of this process (KiB): VmHWM belongs to the address space exec created (ru_maxrss
# would also count the parent's pages the child had between fork and exec).
_PEAK = "print(open('/proc/self/status').read().split('VmHWM:')[1].split()[0])"
_BARE = _PEAK
#: The onboard process's driver: a module of that name in a temporary folder.
_DRIVER = "nemesys_onboard_driver"
# Each argument: frame hex, then the state the agent received it in (x, y, z, heading, speed,
# t, segment or -), comma-separated; ";" separates frames of one scenario.
_ONBOARD = (
    """
import sys
CONSOLE = ("analysis", "backend", "bench", "cli", "rosbridge", "sim", "station")
from planner import VehicleState
from onboard.agent import OnboardAgent
from onboard.guidance import Guidance
corrected = []
for case in sys.argv[1:]:
    agent = OnboardAgent(Guidance())
    for item in case.split(";"):
        f = item.split(",")
        state = VehicleState(*map(float, f[1:7]), None if f[7] == "-" else int(f[7]))
        ack, ref = agent.receive(int(f[0], 16), 100, state)
        if ack["outcome"] != "accepted" or ref is None:
            raise SystemExit(ack["detail"])
        corrected.append(ack["corrected_bits"])
console = [m for m in sys.modules if m.partition(".")[0] in CONSOLE]
if console:
    raise SystemExit(f"the onboard process loaded {console}")
print(*corrected)
"""
    + _PEAK
)


def compile_onboard(python: str | None = None) -> None:
    """Write the onboard packages' bytecode for ``python`` (default this interpreter), as
    installing them on a vehicle does."""
    compile_packages(ONBOARD_PACKAGES, python)


def onboard_arguments(seed: int = 15) -> list[str]:
    """One argument per scenario: its first and retask frames, with the codeword bit errors of
    :data:`MEMORY_ERRORS`, and the states the agent received them in (from a full run's
    acknowledgments)."""
    rng = random.Random(seed)
    args = []
    for name in RETASK_SCENARIOS:
        sc = SCENARIOS[name]
        result = run_scenario(name)
        items = []
        for k, errors in zip((0, sc.retask), MEMORY_ERRORS[name], strict=True):
            ack = result.acks[k]
            s = ack["from"]
            seg = "-" if s["segment"] is None else str(s["segment"])
            fields = (s["x_m"], s["y_m"], s["z_m"], s["heading_deg"], s["speed_mps"], s["t_s"])
            frame = format(with_errors(int(ack["frame_hex"], 16), errors, rng), "025x")
            items.append(",".join([frame, *(repr(float(v)) for v in fields), seg]))
        args.append(";".join(items))
    return args


def measure_memory(
    runs: int, python: str | None = None, args: list[str] | None = None
) -> tuple[int, int, tuple[int, ...]]:
    """Median peak RSS (KiB) of a plain interpreter and of the onboard decode + replan of the
    three scenarios' frames with bit errors, ``runs`` fresh processes each, interleaved; and
    the bits the agent corrected per frame. ``python``: the interpreter measured (default
    this one); ``args``: :func:`onboard_arguments`, if already made.

    Raises:
        RuntimeError: the agent did not correct exactly the errors put in the frames.
    """
    compile_onboard(python)
    if args is None:
        args = onboard_arguments()
    expected = tuple(e for name in RETASK_SCENARIOS for e in MEMORY_ERRORS[name])
    bare: list[int] = []
    onboard: list[int] = []
    corrected: tuple[int, ...] = ()
    with tempfile.TemporaryDirectory() as folder:
        # The driver is a module, compiled like the packages and imported, as a vehicle's node
        # is: run as ``-c`` source, compiling it would cost the onboard process's peak some
        # 60 KiB of parser and compiler memory that no vehicle spends.
        driver = Path(folder) / f"{_DRIVER}.py"
        driver.write_text(_ONBOARD, encoding="utf-8")
        compile_packages([str(driver)], python)
        path = f"sys.path.insert(0, {folder!r})\n"
        for _ in range(runs):
            bare.append(peak_rss_run(path + _BARE, args, python)[0])
            peak, printed = peak_rss_run(path + f"import {_DRIVER}", args, python)
            onboard.append(peak)
            corrected = tuple(int(c) for c in printed[-1].split())
            if corrected != expected:
                raise RuntimeError(f"the agent corrected {corrected}, expected {expected}")
    return int(statistics.median(bare)), int(statistics.median(onboard)), corrected
