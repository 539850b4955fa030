"""Regenerate the committed BCH oracle vectors with the ``galois`` library.

The output, ``tests/codec/data/bch_galois_vectors.json``, is an independent oracle for our
BCH codec: encodings and decodings of the binary BCH codes over GF(2^8) (primitive polynomial
x^8 + x^4 + x^3 + x^2 + 1 = 0x11d) with t = 1, 2, 3, 4, i.e. the narrow-sense primitive
BCH(255, 255 - 8t) codes shortened to a 56-bit message, so n = 56 + 8t (64, 72, 80, 88).

For each code the file records
  * the generator polynomial g(x) as an integer (bit i = coefficient of x^i);
  * 100 systematic encodings (message, then parity; everything highest degree / MSB first),
    a few fixed messages first, then random ones;
  * 40 decodings for every error weight w = 0 .. t + 2: a random message is encoded, w distinct
    random codeword bits are flipped, and galois' decode output (message and number of corrected
    errors, -1 when it reports failure) is recorded as is, including miscorrections.

``galois`` is NOT a project dependency (it pulls in numba). Run this script with a separate
virtual environment that has it, from the repository root, e.g.::

    python3 -m venv /tmp/galois-venv && /tmp/galois-venv/bin/pip install galois
    /tmp/galois-venv/bin/python scripts/gen_bch_vectors.py

The random stream is seeded with a fixed seed, so reruns (with the same galois version) produce
byte-identical output. Only galois, numpy and the standard library are used.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import random
import sys
import time
from pathlib import Path
from typing import Any

import galois
import numpy as np

SEED = 20240917
M = 8  # GF(2^m)
FULL_N = 2**M - 1  # 255
PRIM_POLY = 0x11D  # x^8 + x^4 + x^3 + x^2 + 1, galois' default for GF(2^8)
K = 56  # message bits of every shortened code
T_VALUES = (1, 2, 3, 4)
N_ENCODINGS = 100
N_DECODINGS_PER_WEIGHT = 40
FIXED_MESSAGES = (
    0x00000000000001,
    0x0123456789ABC0,
    0xFFFFFFFFFFFFF0,
    0x80000000000000,
    0x00000000000000,
)

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUTPUT = REPO_ROOT / "tests" / "codec" / "data" / "bch_galois_vectors.json"

# stats[t][w] = [number of decodings with n_corrected == -1, number of miscorrections]
Stats = dict[int, dict[int, list[int]]]


def int_to_bits(value: int, width: int) -> list[int]:
    """Bits of ``value``, most significant (highest degree) first, ``width`` of them."""
    if value < 0 or value >> width:
        raise ValueError(f"{value:#x} does not fit in {width} bits")
    return [(value >> (width - 1 - i)) & 1 for i in range(width)]


def bits_to_int(bits: Any) -> int:
    """Integer from a sequence of bits given most significant (highest degree) first."""
    value = 0
    for bit in bits:
        value = (value << 1) | int(bit)
    return value


def to_hex(value: int, n_bits: int) -> str:
    """Lower-case hex, zero-padded to ``n_bits / 4`` digits."""
    return f"{value:0{n_bits // 4}x}"


def poly_mod_gf2(value: int, modulus: int) -> int:
    """Remainder of the GF(2)[x] polynomial ``value`` divided by ``modulus`` (bit i = x^i)."""
    deg = modulus.bit_length() - 1
    while value.bit_length() - 1 >= deg:
        value ^= modulus << (value.bit_length() - 1 - deg)
    return value


class ShortenedBCH:
    """A galois BCH(255, 255 - 8t) code used shortened to K message bits."""

    def __init__(self, t: int) -> None:
        self.t = t
        full_k = FULL_N - M * t
        self.code = galois.BCH(FULL_N, full_k)
        code = self.code
        assert (code.n, code.k, code.t) == (FULL_N, full_k, t), (code.n, code.k, code.t)
        assert int(code.extension_field.irreducible_poly) == PRIM_POLY, (
            code.extension_field.irreducible_poly
        )
        self.generator = int(code.generator_poly)
        assert code.generator_poly.degree == code.n - code.k == M * t, code.generator_poly
        self.n = K + M * t
        assert self.generator.bit_length() - 1 == self.n - K

    def encode(self, message: int) -> int:
        codeword = self.code.encode(galois.GF2(int_to_bits(message, K)))
        assert codeword.shape == (self.n,), codeword.shape
        value = bits_to_int(codeword)
        # Independent sanity checks: systematic layout and divisibility by g(x).
        assert value >> (self.n - K) == message, (hex(message), hex(value))
        assert poly_mod_gf2(value, self.generator) == 0, hex(value)
        return value

    def decode(self, received: int) -> tuple[int | None, int]:
        """(message or None when galois reports failure, galois' n_corrected)."""
        message, n_corrected = self.code.decode(
            galois.GF2(int_to_bits(received, self.n)), errors=True
        )
        n_corr = int(np.asarray(n_corrected))
        if n_corr == -1:
            return None, -1
        assert n_corr >= 0, n_corr
        assert message.shape == (K,), message.shape
        return bits_to_int(message), n_corr


def code_vectors(t: int, rng: random.Random, stats: Stats) -> dict[str, Any]:
    """The JSON entry of the t-error-correcting code; tallies failures/miscorrections in stats."""
    bch = ShortenedBCH(t)
    n = bch.n
    if t == 2:
        assert bch.generator == 0x16F63, hex(bch.generator)
        assert bch.encode(0x00000000000001) == 0x000000000000016F63
        assert bch.encode(0x0123456789ABC0) == 0x0123456789ABC0C936

    messages = list(FIXED_MESSAGES)
    messages += [rng.getrandbits(K) for _ in range(N_ENCODINGS - len(messages))]
    encodings = [
        {"message": to_hex(msg, K), "codeword": to_hex(bch.encode(msg), n)} for msg in messages
    ]

    decodings: list[dict[str, Any]] = []
    for w in range(t + 3):
        failed = miscorrected = 0
        for _ in range(N_DECODINGS_PER_WEIGHT):
            original = rng.getrandbits(K)
            error = 0
            for pos in rng.sample(range(n), w):
                error |= 1 << pos
            received = bch.encode(original) ^ error
            got, n_corrected = bch.decode(received)
            if w <= t:
                assert got == original and n_corrected == w, (t, w, hex(received), got, n_corrected)
            if got is None:
                failed += 1
            elif got != original:
                miscorrected += 1
            decodings.append(
                {
                    "received": to_hex(received, n),
                    "n_errors": w,
                    "n_corrected": n_corrected,
                    "message": None if got is None else to_hex(got, K),
                }
            )
        stats[t][w] = [failed, miscorrected]

    return {
        "t": t,
        "m": M,
        "prim_poly": f"{PRIM_POLY:#x}",
        "n": n,
        "k": K,
        "generator_poly": f"{bch.generator:#x}",
        "encodings": encodings,
        "decodings": decodings,
    }


def render(doc: dict[str, Any]) -> str:
    """JSON text with one vector per line: compact, yet diff- and grep-friendly."""
    lines = ["{"]
    for key in ("source", "galois_version", "seed"):
        lines.append(f" {json.dumps(key)}: {json.dumps(doc[key])},")
    lines.append(' "codes": [')
    for ci, code in enumerate(doc["codes"]):
        lines.append("  {")
        for key in ("t", "m", "prim_poly", "n", "k", "generator_poly"):
            lines.append(f"   {json.dumps(key)}: {json.dumps(code[key])},")
        for key in ("encodings", "decodings"):
            lines.append(f"   {json.dumps(key)}: [")
            entries = code[key]
            for ei, entry in enumerate(entries):
                comma = "," if ei < len(entries) - 1 else ""
                lines.append(f"    {json.dumps(entry)}{comma}")
            lines.append("   ]," if key == "encodings" else "   ]")
        lines.append("  }," if ci < len(doc["codes"]) - 1 else "  }")
    lines.append(" ]")
    lines.append("}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT, help="JSON file to write")
    args = parser.parse_args(argv)

    start = time.monotonic()
    rng = random.Random(SEED)
    stats: Stats = {t: {} for t in T_VALUES}
    doc: dict[str, Any] = {
        "source": "scripts/gen_bch_vectors.py",
        # == galois.__version__, which galois does not explicitly export (mypy --strict).
        "galois_version": importlib.metadata.version("galois"),
        "seed": SEED,
        "codes": [code_vectors(t, rng, stats) for t in T_VALUES],
    }
    text = render(doc)
    assert json.loads(text) == doc, "rendered JSON does not round-trip"

    output: Path = args.output
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(text, encoding="utf-8")

    print(f"galois {doc['galois_version']}, seed {SEED}: wrote {output}")
    for code in doc["codes"]:
        t = code["t"]
        print(f"  t={t} (n={code['n']}, k={code['k']}) g(x)={code['generator_poly']}")
        for w, (failed, miscorrected) in stats[t].items():
            print(f"    w={w}: n_corrected=-1: {failed:2d}, miscorrected: {miscorrected:2d}")
    print(f"done in {time.monotonic() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
