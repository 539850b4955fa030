"""The onboard path (decode + replan) imports no numpy, so it fits the vehicle's budget."""

from __future__ import annotations

import subprocess
import sys

ONBOARD = (
    "from codec import decode_frame, encode_frame; from planner import VehicleState, plan; "
    "c = decode_frame(encode_frame('helix', speed=0.5, start_depth=2, end_depth=8, radius=5, "
    "turns=3, direction='cw').frame.bits).command; "
    "p = plan(c, VehicleState(0, 0, 2, 0, 0.5)); assert len(p.path) > 10"
)


def _modules_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print('\\n'.join(sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    )
    return set(result.stdout.split())


def test_decode_and_replan_load_no_numpy() -> None:
    loaded = _modules_after(ONBOARD)
    assert {"codec", "planner"} <= loaded
    assert not any(m == "numpy" or m.startswith("numpy.") for m in loaded)


def test_probe_sees_numpy_when_it_is_imported() -> None:
    """Guards the test above against passing because the probe itself is broken."""
    assert "numpy" in _modules_after(ONBOARD + "; import numpy")


#: The console's modules: estimates, sampling, geofences, the override checks. The vehicle's
#: replan and validation against its limits load none of them.
CONSOLE_ONLY = ("planner._estimate", "planner._sampling", "planner._fence", "planner._checks")


def _replan_and_validate() -> str:
    """A statement that replans a decoded helix and validates it against default limits, as
    the onboard agent does (the command is built from its codes: no encoding)."""
    from codec import encode_frame

    codes = encode_frame(
        "helix", speed=0.5, start_depth=2, end_depth=8, radius=5, turns=3, direction="cw"
    ).command.codes
    return (
        "from codec import DICTIONARY, Command; "
        "from planner import Limits, VehicleState, plan, validate; "
        f"c = Command(DICTIONARY['helix'], {codes!r}); "
        "p = plan(c, VehicleState(0, 0, 2, 0, 0.5)); assert validate(p, Limits()) == ()"
    )


def test_the_vehicles_replan_loads_no_console_module() -> None:
    loaded = _modules_after(_replan_and_validate())
    assert {"planner._plan", "planner._limits"} <= loaded
    for name in CONSOLE_ONLY:
        assert name not in loaded, f"{name} is loaded by the onboard replan"


def test_console_modules_load_on_first_use() -> None:
    """Guards the test above: each console module is loaded by the names it holds."""
    loaded = _modules_after(
        _replan_and_validate() + "; "
        "from planner import CircleFence, check, estimate; p.path.sample(0.0); estimate(p); "
        "check(p, Limits(geofence=CircleFence(100.0)))"
    )
    assert set(CONSOLE_ONLY) <= loaded
