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


#: Modules the onboard path must not load: dataclasses drags in inspect, ast, dis and tokenize,
#: typing and decimal are large, numpy is the batch path's. See codec._record.
HEAVY = ("dataclasses", "typing", "decimal", "inspect", "numpy")


def test_decoding_a_frame_loads_no_heavy_module() -> None:
    bare = _modules_after("pass")
    loaded = _modules_after(
        "import codec; "
        "enc = codec.encode_frame('circle', speed=0.5, depth=2, radius=5, direction='cw'); "
        "codec.decode_frame(enc.frame.bits); "
        "codec.decode_frame(enc.frame.value ^ 0b101 << 10); "
        "codec.FrameReceiver().feed_bits(enc.frame.bits)"
    )
    assert "codec._frame" in loaded
    for name in HEAVY:
        assert name not in loaded or name in bare, f"{name} is loaded by the onboard path"


def test_listing_helpers_load_on_first_use() -> None:
    assert "codec._describe" not in _modules_after("import codec")
    loaded = _modules_after("from codec import markdown_tables; markdown_tables()")
    assert "codec._describe" in loaded
