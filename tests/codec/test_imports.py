"""The onboard path (frame sync + decode) must stay light: importing ``codec`` loads no numpy
(only ``codec.batch``, the Monte Carlo path, does)."""

from __future__ import annotations

import subprocess
import sys


def _modules_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print('\\n'.join(sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    )
    return set(result.stdout.split())


def test_codec_imports_no_numpy() -> None:
    loaded = _modules_after("import codec")
    assert "codec" in loaded
    assert not any(m == "numpy" or m.startswith("numpy.") for m in loaded)


def test_batch_path_does_use_numpy() -> None:
    """Guards the test above against passing because the probe itself is broken."""
    assert "numpy" in _modules_after("import codec.batch")
