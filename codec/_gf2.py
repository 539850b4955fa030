"""Polynomials over GF(2) and the finite field GF(2^m), as Python ints.

Convention used everywhere in the codec: a polynomial is an ``int`` whose bit ``i`` is the
coefficient of ``x^i``. A bit string sent MSB first is therefore the polynomial whose
highest-degree coefficient goes on the wire first (the convention of bchlib and galois).
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Sequence


def degree(poly: int) -> int:
    """Degree of a non-zero polynomial (``-1`` for the zero polynomial)."""
    return poly.bit_length() - 1


def poly_mod(value: int, modulus: int) -> int:
    """Remainder of ``value(x)`` divided by ``modulus(x)`` (bit-serial; for tables and tests)."""
    deg_m = degree(modulus)
    while value and degree(value) >= deg_m:
        value ^= modulus << (degree(value) - deg_m)
    return value


def poly_mul(a: int, b: int) -> int:
    """Carry-less product of two polynomials."""
    result = 0
    while b:
        if b & 1:
            result ^= a
        a <<= 1
        b >>= 1
    return result


class ChunkedRemainder:
    """``(value(x) * x^shift) mod modulus(x)`` for ``width``-bit values, by byte tables.

    The remainder is linear in ``value``, so the value is cut into bytes and the remainders
    of the bytes (one 256-entry table per byte position) are XORed: the byte-table CRC idea,
    used here for the CRC-4, the BCH parity and the BCH syndrome. Indexing the bytes of
    ``value.to_bytes()`` is several times faster in CPython than shifting and masking.

    ``share``: another remainder by the same modulus whose tables are reused where they
    cover the same bit positions (equal tables are then the same objects).

    Memory: the tables are packed by :func:`linear_table`, 1, 2 or 4 bytes an entry instead
    of a list slot and, above 256, an int object (~40 bytes in all). For the BCH code's nine
    16-bit tables and the CRC's seven that is about 90 KiB of the vehicle's budget.
    """

    __slots__ = ("_msb_first", "_nbytes", "modulus", "shift", "width")

    def __init__(
        self, modulus: int, width: int, shift: int = 0, share: ChunkedRemainder | None = None
    ) -> None:
        self.modulus = modulus
        self.width = width
        self.shift = shift
        self._nbytes = (width + 7) // 8
        # A table depends only on the modulus and the bit offset of its byte, so a remainder
        # over an overlapping range (the BCH syndrome over the parity's message bytes) can
        # reuse another's tables instead of holding equal copies.
        known: dict[int, Sequence[int]] = {}
        if share is not None and share.modulus == modulus:
            for j, shared in enumerate(reversed(share.tables)):
                known[8 * j + share.shift] = shared
        tables = []
        for j in range(self._nbytes):
            offset = 8 * j + shift
            table = known.get(offset)
            if table is None:
                units = [poly_mod(1 << (offset + i), modulus) for i in range(8)]
                table = known[offset] = linear_table(units, degree(modulus))
            tables.append(table)
        self._msb_first: tuple[Sequence[int], ...] = tuple(reversed(tables))

    @property
    def tables(self) -> tuple[Sequence[int], ...]:
        """One 256-entry table per byte of the value, most significant byte first."""
        return self._msb_first

    def __call__(self, value: int) -> int:
        rem = 0
        for table, byte in zip(self._msb_first, value.to_bytes(self._nbytes, "big"), strict=True):
            rem ^= table[byte]
        return rem


def linear_table(unit_images: Sequence[int], bits: int | None = None) -> Sequence[int]:
    """Table of a GF(2)-linear map on ``len(unit_images)``-bit inputs, from the unit vectors.

    With ``bits`` (every image below ``2^bits``, at most 32) the table is packed: a read-only
    ``memoryview`` of unsigned 8-, 16- or 32-bit ints (native order; no module to import, and
    numpy reads it as an array), filled in place so that building it leaves no garbage behind
    (freed small objects keep their pages resident). Indexing it gives the same ints as the
    list it is without ``bits``.
    """
    size = 1 << len(unit_images)
    table: list[int] | memoryview
    if bits is None or bits > 32:
        table = [0] * size
    elif bits <= 8:
        table = memoryview(bytearray(size))
    elif bits <= 16:
        table = memoryview(bytearray(2 * size)).cast("H")
    else:
        table = memoryview(bytearray(4 * size)).cast("I")
    for v in range(1, size):
        low = v & -v
        table[v] = table[v ^ low] ^ unit_images[low.bit_length() - 1]
    return table.toreadonly() if isinstance(table, memoryview) else table


class GF2m:
    """GF(2^m) with exp/log tables, built from a primitive polynomial.

    Attributes:
        m: extension degree.
        prim_poly: primitive polynomial (bit ``i`` = coefficient of ``x^i``).
        order: ``2^m - 1``, the multiplicative order of the primitive element alpha.
    """

    __slots__ = ("exp", "log", "m", "order", "prim_poly")

    def __init__(self, m: int, prim_poly: int) -> None:
        if degree(prim_poly) != m:
            raise ValueError(f"primitive polynomial {prim_poly:#x} does not have degree {m}")
        self.m = m
        self.prim_poly = prim_poly
        self.order = (1 << m) - 1
        exp = [0] * (2 * self.order)
        log = [0] * (1 << m)
        x = 1
        for i in range(self.order):
            if x == 1 and i:
                raise ValueError(f"{prim_poly:#x} is not primitive: alpha has order {i}")
            exp[i] = x
            log[x] = i
            x <<= 1
            if x >> m:
                x ^= prim_poly
        if x != 1:
            raise ValueError(f"{prim_poly:#x} is not primitive")
        exp[self.order :] = exp[: self.order]
        self.exp = exp
        self.log = log

    def mul(self, a: int, b: int) -> int:
        if a == 0 or b == 0:
            return 0
        return self.exp[self.log[a] + self.log[b]]

    def div(self, a: int, b: int) -> int:
        if b == 0:
            raise ZeroDivisionError("division by zero in GF(2^m)")
        if a == 0:
            return 0
        return self.exp[(self.log[a] - self.log[b]) % self.order]

    def pow_alpha(self, e: int) -> int:
        """alpha^e for any integer e."""
        return self.exp[e % self.order]

    def minimal_poly(self, e: int) -> int:
        """Minimal polynomial over GF(2) of alpha^e (product over its cyclotomic coset)."""
        coset = []
        c = e % self.order
        while c not in coset:
            coset.append(c)
            c = (c * 2) % self.order
        # Multiply (x - alpha^c) over the coset with coefficients in GF(2^m).
        coeffs = [1]  # coeffs[i] = coefficient of x^i
        for c in coset:
            root = self.exp[c]
            nxt = [0] * (len(coeffs) + 1)
            for i, a in enumerate(coeffs):
                nxt[i + 1] ^= a
                nxt[i] ^= self.mul(a, root)
            coeffs = nxt
        poly = 0
        for i, a in enumerate(coeffs):
            if a not in (0, 1):
                raise ArithmeticError("minimal polynomial has a coefficient outside GF(2)")
            poly |= a << i
        return poly
