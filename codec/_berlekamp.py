"""The textbook BCH decoder of :class:`codec.BCHCode`: syndromes, Berlekamp-Massey for the
error locator, Chien search for its roots; and the table of every correctable syndrome.

The vehicle decodes with :class:`codec.TableDecoder` (byte tables and a closed-form
corrector), so this module is loaded only when :meth:`codec.BCHCode.decode` or
:attr:`codec.TableDecoder.error_patterns` is first used: the reference decoder the tests
cross-check the fast one against, the batch path's table, and codes with t > 2.
"""

from __future__ import annotations

from codec._errors import UNCORRECTABLE

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec._bch import BCHCode


def syndromes(code: BCHCode, rem: int) -> list[int]:
    """S_1 .. S_2t of a word whose remainder mod g(x) is ``rem``.

    g(alpha^j) = 0, so r(alpha^j) = (r mod g)(alpha^j): the short remainder is evaluated.
    """
    exp, order = code.field.exp, code.field.order
    powers = []
    while rem:
        low = rem & -rem
        powers.append(low.bit_length() - 1)
        rem ^= low
    synd = [0] * (2 * code.t)
    for j in range(1, 2 * code.t + 1, 2):
        s = 0
        for i in powers:
            s ^= exp[(i * j) % order]
        synd[j - 1] = s
    for j in range(2, 2 * code.t + 1, 2):  # binary code: S_2j = S_j^2
        synd[j - 1] = code.field.mul(synd[j // 2 - 1], synd[j // 2 - 1])
    return synd


def error_locator(code: BCHCode, synd: list[int]) -> list[int]:
    """Berlekamp-Massey: coefficients of Lambda(x), constant term first."""
    f = code.field
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


def chien_search(code: BCHCode, lam: list[int]) -> list[int] | None:
    """Error positions (bit indices, 0 = last parity bit) or ``None`` if Lambda does not
    have exactly deg(Lambda) distinct roots inside the shortened length."""
    f = code.field
    terms = [(j, f.log[c]) for j, c in enumerate(lam) if c and j]
    positions = []
    for i in range(code.n):  # error at x^i <=> Lambda(alpha^-i) = 0
        value = lam[0]
        for j, log_c in terms:
            value ^= f.exp[(log_c - i * j) % f.order]
        if value == 0:
            positions.append(i)
    return positions if len(positions) == len(lam) - 1 else None


def decode(code: BCHCode, received: int) -> tuple[int, int]:
    """:meth:`BCHCode.decode` of a ``received`` word of at most ``n`` bits."""
    rem = code.remainder(received)
    if rem == 0:
        return received >> code.r, 0
    lam = error_locator(code, syndromes(code, rem))
    if len(lam) - 1 > code.t:
        return received >> code.r, UNCORRECTABLE
    positions = chien_search(code, lam)
    if positions is None:
        return received >> code.r, UNCORRECTABLE
    for i in positions:
        received ^= 1 << i
    return received >> code.r, len(positions)


def correctable_errors(code: BCHCode) -> dict[int, int]:
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
