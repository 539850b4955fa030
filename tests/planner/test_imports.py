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
