"""Binary BCH codes over GF(2^m), shortened, systematic, MSB first.

:class:`BCHCode` is the textbook code of the NemeSys paper for any ``t``: the generator is the
least common multiple of the minimal polynomials of alpha^1 .. alpha^2t, encoding appends
``(m(x) * x^r) mod g(x)`` to the message, and decoding computes the syndromes, runs
Berlekamp-Massey for the error locator and finds its roots by Chien search (in
:mod:`codec._berlekamp`, loaded on first use: the vehicle decodes with the table decoder).

:class:`TableDecoder` is the fast path for codes with t <= 2 and a 16-bit (or shorter)
remainder, such as the default (72, 56) code: the remainder of the received word modulo g(x)
is a complete syndrome, taken by byte tables, and a non-zero one is solved in closed form
(:func:`make_corrector`) instead of by Berlekamp-Massey and Chien search. Both are
bounded-distance decoders: they correct every pattern of weight <= t and accept or reject
every other pattern identically (the tests cross-check them and the bchlib and galois
oracles).

Bit conventions: codewords and messages are ``int``; bit i is the coefficient of x^i, so the
highest-degree bit is sent first. A codeword is ``message << r | parity``, r = n - k.
"""

from __future__ import annotations

from codec._errors import UNCORRECTABLE
from codec._gf2 import ChunkedRemainder, GF2m, degree, linear_table, poly_mul

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence

    #: The closed form's tables for t = 2 (see :func:`closed_form_tables`).
    ClosedForm = tuple[
        tuple[int, ...], tuple[int, ...], Sequence[int], bytes,
        tuple[int, ...], tuple[int, ...], int, int, tuple[int, ...],
    ]  # fmt: skip

#: Primitive polynomial of GF(2^8): x^8 + x^4 + x^3 + x^2 + 1 (bchlib's and galois' default).
PRIM_POLY_GF256 = 0x11D


class BCHCode:
    """Narrow-sense binary BCH code of designed distance 2t + 1, shortened to ``k`` bits.

    Args:
        t: number of correctable bit errors.
        k: message length in bits (the full code is shortened by ``2^m - 1 - n``).
        m: extension degree of the field.
        prim_poly: primitive polynomial of GF(2^m).

    Attributes:
        n: codeword length (``k + r``).
        k: message length.
        t: correctable errors.
        d: designed minimum distance ``2t + 1``.
        r: parity bits, the degree of the generator.
        generator_poly: g(x) (bit i = coefficient of x^i).
    """

    def __init__(self, t: int, k: int = 56, m: int = 8, prim_poly: int = PRIM_POLY_GF256) -> None:
        if t < 1:
            raise ValueError("t must be at least 1")
        self.field = GF2m(m, prim_poly)
        g = 1
        done: set[int] = set()
        for i in range(1, 2 * t + 1):
            coset_rep = min(i * (1 << j) % self.field.order for j in range(m))
            if coset_rep not in done:
                done.add(coset_rep)
                g = poly_mul(g, self.field.minimal_poly(i))
        self.t = t
        self.k = k
        self.m = m
        self.r = degree(g)
        self.n = k + self.r
        self.d = 2 * t + 1
        self.generator_poly = g
        if self.n > self.field.order:
            raise ValueError(f"n = {self.n} exceeds the full length {self.field.order}")
        self._parity = ChunkedRemainder(g, width=k, shift=self.r)
        # Bytes 0..k/8-1 of a codeword are the message bytes: the same tables as the parity's.
        self._remainder = ChunkedRemainder(g, width=self.n, share=self._parity)
        self._msg_mask = (1 << k) - 1
        self._cw_mask = (1 << self.n) - 1

    def __repr__(self) -> str:
        return (
            f"<BCH code [{self.n}, {self.k}, {self.d}] over GF(2^{self.m}), t={self.t}, "
            f"g={self.generator_poly:#x}>"
        )

    @property
    def parity_tables(self) -> tuple[Sequence[int], ...]:
        """Byte tables of the parity of a message, most significant message byte first."""
        return self._parity.tables

    @property
    def remainder_tables(self) -> tuple[Sequence[int], ...]:
        """Byte tables of ``received mod g``, most significant codeword byte first."""
        return self._remainder.tables

    def encode(self, message: int) -> int:
        """Systematic codeword of a ``k``-bit message: ``message << r | parity``."""
        if message >> self.k or message < 0:
            raise ValueError(f"message does not fit in {self.k} bits")
        return (message << self.r) | self._parity(message)

    def remainder(self, received: int) -> int:
        """``received(x) mod g(x)``; zero exactly for codewords."""
        return self._remainder(received)

    def syndromes(self, received: int) -> list[int]:
        """S_1 .. S_2t, the received word evaluated at alpha^1 .. alpha^2t."""
        from codec._berlekamp import syndromes  # the textbook decoder: not loaded onboard

        return syndromes(self, self._remainder(received))

    def error_locator(self, synd: list[int]) -> list[int]:
        """Berlekamp-Massey: coefficients of Lambda(x), constant term first."""
        from codec._berlekamp import error_locator

        return error_locator(self, synd)

    def chien_search(self, lam: list[int]) -> list[int] | None:
        """Error positions (bit indices, 0 = last parity bit) or ``None`` if Lambda does not
        have exactly deg(Lambda) distinct roots inside the shortened length."""
        from codec._berlekamp import chien_search

        return chien_search(self, lam)

    def decode(self, received: int) -> tuple[int, int]:
        """Correct up to t errors (syndromes, Berlekamp-Massey, Chien search).

        Returns:
            ``(message, n_corrected)``; ``n_corrected`` is :data:`UNCORRECTABLE` (-1) when
            the word is beyond the decoder's reach, and ``message`` is then the uncorrected
            message bits.
        """
        from codec._berlekamp import decode

        return decode(self, received & self._cw_mask)


class TableDecoder:
    """Syndrome-table decoder for a (72, 56)-shaped code with t <= 2 (the default code).

    The remainder of the received word modulo g(x) is a complete syndrome for these codes. It
    is the XOR of one byte-table lookup per message byte and the parity bytes themselves (their
    remainder is themselves: degree < r). A non-zero remainder is then solved in closed form
    (:func:`make_corrector`): S1 and S3 by four byte lookups, the error locator's roots from
    one table per c of y^2 + y = c. Memory: the message bytes' tables as tuples (indexing a
    tuple is about twice as fast as the code's packed tables; 7 x 256 entries, about 70 KiB,
    or none when given the frame's, which carry its CRC check too) and a few KiB of
    ``bytes`` and tuple tables for the correction, built with the decoder: a word with errors
    allocates nothing but its result. (A dictionary from every correctable syndrome to its
    pattern, 2628 entries, costs about 300 KiB of resident memory; :attr:`error_patterns`
    still builds it on demand, for the numpy batch path and the tests, but the decoders never
    use it.)

    Args:
        code: the code, 72 bits with t <= 2 and r = 8 or 16.
        message_tables: byte tables of the message bytes, most significant first, whose bits
            0 .. r-1 are the code's remainder tables' (bits above are ignored, so a frame can
            pack a check of its own there and share them); default: the code's, as tuples.
    """

    N_BYTES = 9

    def __init__(
        self, code: BCHCode, message_tables: Sequence[Sequence[int]] | None = None
    ) -> None:
        if code.t > 2 or code.r > 16 or code.r % 8 or code.n != 8 * self.N_BYTES:
            raise ValueError(
                "the table decoder handles 72-bit codes with t <= 2 and r = 8 or 16 parity bits"
            )
        self.code = code
        self._errors: dict[int, int] | None = None
        k_bytes = code.k // 8
        own = code.remainder_tables[:k_bytes]
        if message_tables is None:
            message_tables = tuple(tuple(table) for table in own)
        elif len(message_tables) != k_bytes or any(
            len(mine) != 256
            or any((a & ((1 << code.r) - 1)) != b for a, b in zip(mine, table, strict=True))
            for mine, table in zip(message_tables, own, strict=True)
        ):
            raise ValueError("message_tables are not the code's remainder tables")
        #: The message bytes' tables the decoders index (bits 0 .. r-1: the remainder).
        self.message_tables: tuple[Sequence[int], ...] = tuple(message_tables)
        self.decode: Callable[[int], tuple[int, int]]
        self.decode_bytes: Callable[[bytes], tuple[int, int]]
        #: Non-zero remainder -> the correctable error pattern, or ``None`` (closed form).
        self.correct: Callable[[int], int | None]
        #: The closed form's tables (t = 2, :func:`closed_form_tables`), else ``None``.
        self.closed_form: ClosedForm | None = None
        if code.t == 2 and code.r == 16:
            self.closed_form = closed_form_tables(code)
            self.correct = _t2_corrector(self.closed_form)
            self.decode, self.decode_bytes = _make_t2_decoders(
                self.message_tables, self.closed_form
            )
        else:
            self.correct = make_corrector(code)
            self.decode, self.decode_bytes = _make_decoders(
                code.remainder_tables, code.r, self.correct
            )
        self.decode.__doc__ = """Same contract as :meth:`BCHCode.decode`."""
        self.decode_bytes.__doc__ = """Decode the codeword as 9 bytes, MSB first (the wire form).

        Same result as :meth:`decode` of ``int.from_bytes(codeword, "big")``."""

    @property
    def error_patterns(self) -> Mapping[int, int]:
        """Non-zero syndrome (remainder mod g) -> the correctable error pattern it stands for."""
        errors = self._errors
        if errors is None:
            from types import MappingProxyType  # the batch path's and the tests': not onboard

            from codec._berlekamp import correctable_errors

            errors = self._errors = correctable_errors(self.code)
        return MappingProxyType(errors)


def closed_form_tables(code: BCHCode) -> ClosedForm:
    """The tables of the t = 2 closed form (:func:`make_corrector`), m <= 8:

    ``st_lo, st_hi``: S1 | S3 << 8 of the remainder's low and high byte (S = lo ^ hi by
    linearity; one lookup per byte gives both); ``log``: the field's; ``cube``: log of S1^3
    from log of S1. Two errors x1, x2: x1 + x2 = S1 and x1 x2 = S3 / S1 + S1^2, so with x = S1 y the
    locator becomes y^2 + y = c, c = S3 / S1^3 + 1; ``first[k]`` and ``second[k]`` are the
    logs of its two roots y0 and y0 + 1 for c = alpha^k + 1 (k = log S3 - 3 log S1, any
    sign: the tables have 2^m - 1 entries and negative indices wrap), and ``first0`` and
    ``second0`` for c = 1 (S3 = 0). No root (trace of c is 1: more than two errors) is
    :data:`_NO_ROOT` there. ``bit[e]``: the error pattern of the position of log ``e``
    (``e`` below two periods) when it lies inside the shortened codeword, else 0, and 0 for
    every ``e`` from ``_NO_ROOT``: the errors are then ``bit[first[k] + log S1]`` and
    ``bit[second[k] + log S1]``, both non-zero exactly when the word is correctable.
    """
    f = code.field
    exp, order, n = f.exp, f.order, code.n

    def syndrome_tables(j: int) -> list[bytes]:
        """S_j of the remainder's bytes, least significant byte first: ``bytes`` of 256."""
        tables = []
        for b in range(code.r // 8):
            units = [exp[((8 * b + k) * j) % order] for k in range(8)]
            tables.append(bytes(linear_table(units)))  # small ints: no garbage
        return tables

    s1_lo, s1_hi = syndrome_tables(1)
    s3_lo, s3_hi = syndrome_tables(3)
    st_lo = tuple(s1 | s3 << 8 for s1, s3 in zip(s1_lo, s3_lo, strict=True))
    st_hi = tuple(s1 | s3 << 8 for s1, s3 in zip(s1_hi, s3_hi, strict=True))
    root_log = [_NO_ROOT] * (1 << f.m)  # c -> log of a root y of y^2 + y = c (y, y + 1)
    for y in range(2, 1 << f.m):
        root_log[f.mul(y, y) ^ y] = f.log[y]

    def logs(c: int) -> tuple[int, int]:
        first = root_log[c]
        return (first, f.log[exp[first] ^ 1]) if first != _NO_ROOT else (_NO_ROOT, _NO_ROOT)

    pairs = [logs(exp[k] ^ 1) if k else (_NO_ROOT, _NO_ROOT) for k in range(order)]
    first0, second0 = logs(1)
    bit = tuple(1 << e % order if e < 2 * order and e % order < n else 0 for e in range(3 * order))
    return (
        st_lo, st_hi, f.log, bytes(3 * i % order for i in range(order)),
        tuple(p[0] for p in pairs), tuple(p[1] for p in pairs), first0, second0, bit,
    )  # fmt: skip


#: ``first``/``second`` for "no root": with a log of S1 added (at most 2^m - 2) it indexes
#: the zeros at the end of ``bit``.
_NO_ROOT = 510


def make_corrector(code: BCHCode) -> Callable[[int], int | None]:
    """The error pattern of weight 1..t (t <= 2) with a given non-zero remainder mod g(x), or
    ``None`` when there is none inside the (shortened) codeword: bounded-distance decoding,
    the same decisions as :meth:`BCHCode.decode` and as a table of every correctable syndrome.

    In closed form over GF(2^m) (:func:`closed_form_tables`): the syndromes S1 = r(alpha) and
    S3 = r(alpha^3) of the remainder r come from byte tables (linear in r). One error at i:
    S1 = alpha^i and S3 = S1^3. Two errors: the roots of y^2 + y = c from a table by
    c; no root means more than two errors. An error position at or beyond n (outside the
    shortened code) is uncorrectable too. For t = 1 the remainder is S1 itself up to the field
    isomorphism: one error at log S1, if below n.
    """
    f = code.field
    log, order, n = f.log, f.order, code.n
    if code.t > 2 or f.m > 8 or code.r % 8 or 2 * order > _NO_ROOT:
        raise ValueError("the closed-form corrector handles t <= 2 over GF(2^m), m <= 8")
    if code.t == 1:
        exp = f.exp
        (s1_table,) = [
            bytes(linear_table([exp[(8 * b + k) % order] for k in range(8)]))
            for b in range(code.r // 8)
        ]

        def correct_one(rem: int) -> int | None:
            s1 = s1_table[rem]
            if not s1:
                return None
            i = log[s1]
            return 1 << i if i < n else None

        return correct_one
    return _t2_corrector(closed_form_tables(code))


def _t2_corrector(tables: ClosedForm) -> Callable[[int], int | None]:
    """:func:`make_corrector` for t = 2, from its tables."""
    st_lo, st_hi, log, cube, first, second, first0, second0, bit = tables

    def correct(rem: int) -> int | None:
        st = st_lo[rem & 0xFF] ^ st_hi[rem >> 8]
        s1 = st & 0xFF
        if not s1:
            return None  # S3 != 0 with S1 = 0: at least three errors
        l1 = log[s1]
        s3 = st >> 8
        if s3:
            k = log[s3] - cube[l1]
            if not k:  # S3 = S1^3: one error, at log S1
                return bit[l1] or None
            e1, e2 = bit[first[k] + l1], bit[second[k] + l1]
        else:
            e1, e2 = bit[first0 + l1], bit[second0 + l1]
        return e1 | e2 if e1 and e2 else None

    return correct


# The decoders are closures over their tables: cell variables are read almost as fast as
# locals and, unlike default arguments, cost nothing per call. This is the per-frame hot path.


def _make_t2_decoders(
    tables: Sequence[Sequence[int]], closed_form: ClosedForm
) -> tuple[Callable[[int], tuple[int, int]], Callable[[bytes], tuple[int, int]]]:
    """The (72, 56) t = 2 decoders, the closed form written out (a call costs more than it):
    the same decisions as :func:`make_corrector` (the tests compare every remainder)."""
    t0, t1, t2, t3, t4, t5, t6 = tables
    st_lo, st_hi, log, cube, first, second, first0, second0, bit = closed_form
    from_bytes = int.from_bytes

    def decode_bytes(b: bytes) -> tuple[int, int]:
        w = from_bytes(b, "big")
        b0, b1, b2, b3, b4, b5, b6, _, _ = b  # quicker than indexing seven times
        # The parity bytes are their own remainder: XOR the word in and keep the low 16 bits.
        syn = (t0[b0] ^ t1[b1] ^ t2[b2] ^ t3[b3] ^ t4[b4] ^ t5[b5] ^ t6[b6] ^ w) & 0xFFFF
        if not syn:
            return w >> 16, 0
        st = st_lo[syn & 0xFF] ^ st_hi[syn >> 8]
        s1 = st & 0xFF
        if s1:
            l1 = log[s1]
            s3 = st >> 8
            if s3:
                k = log[s3] - cube[l1]
                if not k:
                    e1 = bit[l1]
                    if e1:
                        return (w ^ e1) >> 16, 1
                    return w >> 16, UNCORRECTABLE
                e1 = bit[first[k] + l1]  # 0: no root (most words with 3 errors) or outside
                if e1:
                    e2 = bit[second[k] + l1]
                    if e2:
                        return (w ^ e1 ^ e2) >> 16, 2
            else:
                e1 = bit[first0 + l1]
                e2 = bit[second0 + l1]
                if e1 and e2:
                    return (w ^ e1 ^ e2) >> 16, 2
        return w >> 16, UNCORRECTABLE

    def decode(received: int) -> tuple[int, int]:
        return decode_bytes(received.to_bytes(9, "big"))

    return decode, decode_bytes


def _make_decoders(
    tables: Sequence[Sequence[int]], r: int, correct: Callable[[int], int | None]
) -> tuple[Callable[[int], tuple[int, int]], Callable[[bytes], tuple[int, int]]]:
    t0, t1, t2, t3, t4, t5, t6, t7, t8 = tables
    from_bytes = int.from_bytes
    k_bytes = 9 - r // 8  # the message bytes of the 9-byte codeword

    def decode(received: int) -> tuple[int, int]:
        b = received.to_bytes(9, "big")
        syn = (
            t0[b[0]] ^ t1[b[1]] ^ t2[b[2]] ^ t3[b[3]] ^ t4[b[4]]
            ^ t5[b[5]] ^ t6[b[6]] ^ t7[b[7]] ^ t8[b[8]]
        )  # fmt: skip
        if not syn:
            return received >> r, 0
        error = correct(syn)
        if error is None:
            return received >> r, UNCORRECTABLE
        return (received ^ error) >> r, error.bit_count()

    def decode_bytes(b: bytes) -> tuple[int, int]:
        syn = (
            t0[b[0]] ^ t1[b[1]] ^ t2[b[2]] ^ t3[b[3]] ^ t4[b[4]]
            ^ t5[b[5]] ^ t6[b[6]] ^ t7[b[7]] ^ t8[b[8]]
        )  # fmt: skip
        if not syn:
            return from_bytes(b[:k_bytes], "big"), 0
        error = correct(syn)
        if error is None:
            return from_bytes(b[:k_bytes], "big"), UNCORRECTABLE
        return (from_bytes(b, "big") ^ error) >> r, error.bit_count()

    return decode, decode_bytes
