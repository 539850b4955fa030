"""Binary BCH codes over GF(2^m), shortened, systematic, MSB first.

:class:`BCHCode` is the textbook code of the NemeSys paper for any ``t``: the generator is the
least common multiple of the minimal polynomials of alpha^1 .. alpha^2t, encoding appends
``(m(x) * x^r) mod g(x)`` to the message, and decoding computes the syndromes, runs
Berlekamp-Massey for the error locator and finds its roots by Chien search.

:class:`TableDecoder` is the fast path for codes with t <= 2 and a 16-bit (or shorter)
remainder, such as the default (72, 56) code: the remainder of the received word modulo g(x)
is a complete syndrome, so a dictionary from remainder to error pattern, holding the
1 + n + n(n-1)/2 correctable patterns, replaces the algebra. Both are bounded-distance
decoders: they correct every pattern of weight <= t and accept or reject every other pattern
identically (the tests cross-check them and the bchlib and galois oracles).

Bit conventions: codewords and messages are ``int``; bit i is the coefficient of x^i, so the
highest-degree bit is sent first. A codeword is ``message << r | parity``, r = n - k.
"""

from __future__ import annotations

from types import MappingProxyType

from codec._gf2 import ChunkedRemainder, GF2m, degree, poly_mul

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence

#: Primitive polynomial of GF(2^8): x^8 + x^4 + x^3 + x^2 + 1 (bchlib's and galois' default).
PRIM_POLY_GF256 = 0x11D

#: ``n_corrected`` returned for a word the decoder cannot correct (galois' convention).
UNCORRECTABLE = -1


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
    def parity_tables(self) -> tuple[list[int], ...]:
        """Byte tables of the parity of a message, most significant message byte first."""
        return self._parity.tables

    @property
    def remainder_tables(self) -> tuple[list[int], ...]:
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
        return self._syndromes_of_remainder(self._remainder(received))

    def _syndromes_of_remainder(self, rem: int) -> list[int]:
        # g(alpha^j) = 0, so r(alpha^j) = (r mod g)(alpha^j): evaluate the short remainder.
        exp, order = self.field.exp, self.field.order
        powers = []
        while rem:
            low = rem & -rem
            powers.append(low.bit_length() - 1)
            rem ^= low
        synd = [0] * (2 * self.t)
        for j in range(1, 2 * self.t + 1, 2):
            s = 0
            for i in powers:
                s ^= exp[(i * j) % order]
            synd[j - 1] = s
        for j in range(2, 2 * self.t + 1, 2):  # binary code: S_2j = S_j^2
            synd[j - 1] = self.field.mul(synd[j // 2 - 1], synd[j // 2 - 1])
        return synd

    def error_locator(self, synd: list[int]) -> list[int]:
        """Berlekamp-Massey: coefficients of Lambda(x), constant term first."""
        f = self.field
        lam = [1]
        prev = [1]
        length = 0
        shift = 1
        prev_disc = 1
        for step, s in enumerate(synd):
            disc = s
            for i in range(1, length + 1):
                if i < len(lam):
                    disc ^= f.mul(lam[i], synd[step - i])
            if disc == 0:
                shift += 1
                continue
            coef = f.div(disc, prev_disc)
            updated = lam + [0] * max(0, len(prev) + shift - len(lam))
            for i, p in enumerate(prev):
                updated[i + shift] ^= f.mul(coef, p)
            if 2 * length <= step:
                prev, prev_disc = lam, disc
                length = step + 1 - length
                shift = 1
            else:
                shift += 1
            lam = updated
        while len(lam) > 1 and lam[-1] == 0:
            lam.pop()
        return lam

    def chien_search(self, lam: list[int]) -> list[int] | None:
        """Error positions (bit indices, 0 = last parity bit) or ``None`` if Lambda does not
        have exactly deg(Lambda) distinct roots inside the shortened length."""
        f = self.field
        terms = [(j, f.log[c]) for j, c in enumerate(lam) if c and j]
        positions = []
        for i in range(self.n):  # error at x^i <=> Lambda(alpha^-i) = 0
            value = lam[0]
            for j, log_c in terms:
                value ^= f.exp[(log_c - i * j) % f.order]
            if value == 0:
                positions.append(i)
        return positions if len(positions) == len(lam) - 1 else None

    def decode(self, received: int) -> tuple[int, int]:
        """Correct up to t errors.

        Returns:
            ``(message, n_corrected)``; ``n_corrected`` is :data:`UNCORRECTABLE` (-1) when
            the word is beyond the decoder's reach, and ``message`` is then the uncorrected
            message bits.
        """
        received &= self._cw_mask
        rem = self._remainder(received)
        if rem == 0:
            return received >> self.r, 0
        lam = self.error_locator(self._syndromes_of_remainder(rem))
        if len(lam) - 1 > self.t:
            return received >> self.r, UNCORRECTABLE
        positions = self.chien_search(lam)
        if positions is None:
            return received >> self.r, UNCORRECTABLE
        for i in positions:
            received ^= 1 << i
        return received >> self.r, len(positions)


class TableDecoder:
    """Syndrome-table decoder for a (72, 56)-shaped code with t <= 2 (the default code).

    The remainder of the received word modulo g(x) is a complete syndrome for these codes. It
    is the XOR of nine byte-table lookups (one per codeword byte), and one dictionary lookup
    then gives the error pattern. Memory: the code's byte tables (9 x 256 entries, 7 of them
    shared with the encoder) and a dictionary of 2628 entries (about 240 KB), built the first
    time a word has a non-zero syndrome: a process that only sees clean frames never holds it.
    """

    N_BYTES = 9

    def __init__(self, code: BCHCode) -> None:
        if code.t > 2 or code.r > 16 or code.r % 8 or code.n != 8 * self.N_BYTES:
            raise ValueError(
                "the table decoder handles 72-bit codes with t <= 2 and r = 8 or 16 parity bits"
            )
        self.code = code
        self._errors: dict[int, int] | None = None
        self.decode: Callable[[int], tuple[int, int]]
        self.decode_bytes: Callable[[bytes], tuple[int, int]]
        self.decode, self.decode_bytes = _make_decoders(
            code.remainder_tables, code.r, self._error_table
        )
        self.decode.__doc__ = """Same contract as :meth:`BCHCode.decode`."""
        self.decode_bytes.__doc__ = """Decode the codeword as 9 bytes, MSB first (the wire form).

        Same result as :meth:`decode` of ``int.from_bytes(codeword, "big")``."""

    def _error_table(self) -> dict[int, int]:
        errors = self._errors
        if errors is None:
            errors = self._errors = _correctable_errors(self.code)
        return errors

    @property
    def error_patterns(self) -> Mapping[int, int]:
        """Non-zero syndrome (remainder mod g) -> the correctable error pattern it stands for."""
        return MappingProxyType(self._error_table())


def _correctable_errors(code: BCHCode) -> dict[int, int]:
    """Syndrome -> error pattern, for every pattern of weight 1 .. t (t <= 2)."""
    single = [code.remainder(1 << i) for i in range(code.n)]
    errors: dict[int, int] = {}
    for i, si in enumerate(single):
        errors[si] = 1 << i
    if code.t == 2:
        for i in range(code.n):
            si, bit = single[i], 1 << i
            for j in range(i + 1, code.n):
                errors[si ^ single[j]] = bit | (1 << j)
    expected = code.n + (code.n * (code.n - 1) // 2 if code.t == 2 else 0)
    if 0 in errors or len(errors) != expected:
        raise ValueError("correctable patterns do not have distinct syndromes")
    return errors


# The decoders are closures over their tables: cell variables are read almost as fast as
# locals and, unlike default arguments, cost nothing per call. This is the per-frame hot path.
# ``get`` starts as a stand-in that builds the error dictionary on the first non-zero syndrome
# and rebinds ``get`` (shared by both decoders) to the dictionary's own lookup: no per-call
# test, and the dictionary costs no memory until a word needs correcting.


def _make_decoders(
    tables: Sequence[list[int]], r: int, error_table: Callable[[], dict[int, int]]
) -> tuple[Callable[[int], tuple[int, int]], Callable[[bytes], tuple[int, int]]]:
    t0, t1, t2, t3, t4, t5, t6, t7, t8 = tables
    from_bytes = int.from_bytes
    k_bytes = 9 - r // 8  # the message bytes of the 9-byte codeword
    get: Callable[[int], int | None]

    def first_lookup(syndrome: int) -> int | None:
        nonlocal get
        get = error_table().get
        return get(syndrome)

    get = first_lookup

    def decode(received: int) -> tuple[int, int]:
        b = received.to_bytes(9, "big")
        syn = (
            t0[b[0]] ^ t1[b[1]] ^ t2[b[2]] ^ t3[b[3]] ^ t4[b[4]]
            ^ t5[b[5]] ^ t6[b[6]] ^ t7[b[7]] ^ t8[b[8]]
        )  # fmt: skip
        if not syn:
            return received >> r, 0
        error = get(syn)
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
        error = get(syn)
        if error is None:
            return from_bytes(b[:k_bytes], "big"), UNCORRECTABLE
        return (from_bytes(b, "big") ^ error) >> r, error.bit_count()

    return decode, decode_bytes
