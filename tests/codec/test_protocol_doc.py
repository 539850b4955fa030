"""docs/protocol.md stays true.

The dictionary tables, the worked example and the delimiter ranking are re-derived from the
code and looked up in the document; every ``console`` session is run through bash (with
``nemesys`` bound to this interpreter's ``cli.main``) and every ``pycon`` session through
doctest, in document order, and their output is compared with the text. When the codec
changes, fix the document with the output these tests print.
"""

from __future__ import annotations

import doctest
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from codec import (
    CODE,
    FIELDS_PER_FRAME,
    ParamValue,
    crc4,
    encode_frame,
    markdown_tables,
    message_of,
    payload_of,
    sections,
)

ROOT = Path(__file__).parents[2]
DOC = ROOT / "docs" / "protocol.md"
DELIMITER_SCRIPT = ROOT / "scripts" / "choose_delimiter.py"
#: Makes ``nemesys`` in a console session mean this interpreter's CLI, installed or not.
CONSOLE_PRELUDE = 'nemesys() { "$NEMESYS_PYTHON" -m cli.main "$@"; }\n'


@pytest.fixture(scope="module")
def doc() -> str:
    return DOC.read_text(encoding="utf-8")


def _blocks(doc: str, lang: str) -> list[tuple[int, str]]:
    """``(line number, body)`` of every fenced block of ``lang``, body ending in a newline."""
    fence = re.compile(rf"^```{re.escape(lang)}\n(.*?)^```$", re.MULTILINE | re.DOTALL)
    return [(doc.count("\n", 0, m.start()) + 1, m.group(1)) for m in fence.finditer(doc)]


def _text(value: ParamValue, unit: str) -> str:
    if isinstance(value, str):
        return value
    return format(float(value), ".10g") + (f" {unit}" if unit else "")


def test_dictionary_tables_are_current(doc: str) -> None:
    assert markdown_tables() in doc, "paste the output of `nemesys patterns --markdown`"


def test_worked_example_is_current(doc: str) -> None:
    enc = encode_frame("square", speed=0.5, depth=2, side_span=12.34, direction="cw")
    command, frame = enc.command, enc.frame
    pattern = command.pattern
    bits = frame.bits
    payload = payload_of(command)
    crc = crc4(payload)
    message = message_of(command)
    codeword = CODE.encode(message)
    parity = codeword & ((1 << CODE.r) - 1)

    expected = [
        bits,
        frame.hex,
        frame.grouped(pattern),
        frame.to_bytes().hex(" "),
        f"= 0x{payload:013x}",
        f"= {crc:04b} (0x{crc:x})",
        f"= 0x{message:014x}",
        f"= {parity:016b} (0x{parity:04x})",
        f"= 0x{codeword:018x}",
        f"| - | pattern ID | {pattern.name} | {pattern.id} | `{pattern.id:04b}` | {pattern.name} |",
    ]
    for j in range(FIELDS_PER_FRAME):
        if j < len(pattern.fields):
            snap, code = enc.snaps[j], command.codes[j]
            requested, sent = _text(snap.requested, snap.unit), _text(snap.sent, snap.unit)
            expected.append(
                f"| j{j + 1} | {snap.field} | {requested} | {code} | `{code:08b}` | {sent} |"
            )
        else:
            expected.append(f"| j{j + 1} | (unused) | - | 0 | `00000000` | - |")
    for s in sections(pattern):
        span = f"{s.start}-{s.start + s.length - 1}"
        expected.append(f"| {span} | {s.name} | `{bits[s.start : s.start + s.length]}` |")
    expected.append(encode_frame("surface").frame.hex)
    missing = [text for text in expected if text not in doc]
    assert not missing, "worked example out of date; missing:\n" + "\n".join(missing)


def test_delimiter_table_is_current(doc: str) -> None:
    run = subprocess.run(
        [sys.executable, str(DELIMITER_SCRIPT)],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    tables = [body for _, body in _blocks(doc, "text") if body.startswith("delimiter ")]
    assert tables == [run.stdout], f"paste the output of scripts/choose_delimiter.py:\n{run.stdout}"


@pytest.mark.slow  # console sessions behind the protocol document, ~1 s
def test_console_sessions(doc: str) -> None:
    sessions = _blocks(doc, "console")
    assert sessions, "no console sessions found"
    env = {**os.environ, "NEMESYS_PYTHON": sys.executable}
    for line, body in sessions:
        commands = [ln[2:] for ln in body.splitlines() if ln.startswith("$ ")]
        expected = [ln.rstrip() for ln in body.splitlines() if not ln.startswith("$ ")]
        run = subprocess.run(
            ["bash", "-c", CONSOLE_PRELUDE + "\n".join(commands)],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            check=False,
            timeout=120,
        )
        got = [ln.rstrip() for ln in run.stdout.splitlines()]
        assert got == expected, f"console session at docs/protocol.md:{line}, got:\n{run.stdout}"


def test_python_sessions(doc: str) -> None:
    sessions = _blocks(doc, "pycon")
    assert sessions, "no pycon sessions found"
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    report: list[str] = []
    globs: dict[str, object] = {"__name__": "protocol_md"}
    failed = 0
    for line, body in sessions:  # one namespace, in document order, like a doctest file
        test = parser.get_doctest(body, globs, f"protocol.md:{line}", str(DOC), line)
        failed += runner.run(test, out=report.append, clear_globs=False).failed
        globs = test.globs  # DocTest works on a copy
    assert failed == 0, "".join(report)
