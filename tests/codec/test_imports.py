"""The onboard path (frame sync + decode) must stay light: importing ``codec`` loads no numpy
(only ``codec.batch``, the Monte Carlo path, does)."""

from __future__ import annotations

import subprocess
import sys

from tests.vehicle_side import ROOT


def _modules_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print('\\n'.join(sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    )
    return set(result.stdout.split())


def plain_modules_after(statement: str) -> set[str]:
    """The modules a plain interpreter (``python -I -S``, the memory benches' baseline: no
    site, no start-up hook) has loaded after ``statement``, the checkout first on the path."""
    code = f"import sys; sys.path.insert(0, {str(ROOT)!r}); {statement}; print(*sys.modules)"
    done = subprocess.run(
        [sys.executable, "-I", "-S", "-c", code], check=True, capture_output=True, text=True
    )
    return set(done.stdout.split())


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


#: The console's modules: encoding, one-frame decode of any form, snapping and the scales'
#: texts, the lookup of a pattern's name, the textbook BCH decoder. The vehicle's decode loads
#: none of them.
CONSOLE_ONLY = ("codec._wire", "codec._parse", "codec._snap", "codec._lookup", "codec._berlekamp")


def _received(errors: int) -> str:
    """A statement feeding the receiver the 13 bytes of a circle frame with ``errors``
    codeword bit errors, as the onboard agent does, and checking what it corrected."""
    from codec import Frame, encode_frame

    value = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame.value
    for k in range(errors):
        value ^= 1 << (20 + 7 * k)  # codeword bits (the guard is the last 4)
    data = Frame(value).to_bytes().hex()
    return (
        f"import codec; events = codec.FrameReceiver().feed_bytes(bytes.fromhex('{data}')); "
        f"assert events[0].decoded.corrected == {errors}, events"
    )


def test_the_vehicles_decode_loads_no_console_module() -> None:
    for errors in (0, 2):
        loaded = _modules_after(_received(errors))
        assert "codec._sync" in loaded
        for name in CONSOLE_ONLY:
            assert name not in loaded, f"{name} is loaded by the onboard decode"


def test_console_modules_load_on_first_use() -> None:
    """Guards the test above: each console module is loaded by the names it holds."""
    loaded = _modules_after(
        "import codec; "
        "enc = codec.encode_frame('circle', speed=0.5, depth=2, radius=5, direction='cw'); "
        "codec.decode_frame(enc.frame.hex); codec.CODE.decode(enc.frame.codeword)"
    )
    assert set(CONSOLE_ONLY) <= loaded
