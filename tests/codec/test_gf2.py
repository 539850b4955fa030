"""GF(2)[x] polynomials, the field GF(2^8) and the byte-table remainder (codec._gf2)."""

from __future__ import annotations

import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codec._gf2 import ChunkedRemainder, GF2m, degree, poly_mod, poly_mul

PRIM = 0x11D  # x^8 + x^4 + x^3 + x^2 + 1
F = GF2m(8, PRIM)


def slow_mul(a: int, b: int) -> int:
    """Field product the schoolbook way: carry-less multiply, then reduce bit by bit."""
    product = 0
    for i in range(8):
        if b >> i & 1:
            product ^= a << i
    for i in range(14, 7, -1):
        if product >> i & 1:
            product ^= PRIM << (i - 8)
    return product


def evaluate(poly: int, x: int) -> int:
    """poly(x) in GF(2^8) for a binary polynomial, by Horner's rule with slow_mul."""
    acc = 0
    for i in range(degree(poly), -1, -1):
        acc = slow_mul(acc, x) ^ (poly >> i & 1)
    return acc


# --- polynomials over GF(2) ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("poly", "expected"),
    [(0, -1), (1, 0), (0b10, 1), (0b11, 1), (0x11D, 8), (0x16F63, 16), (1 << 71, 71)],
)
def test_degree(poly: int, expected: int) -> None:
    assert degree(poly) == expected


@pytest.mark.parametrize(
    ("a", "b", "product"),
    [
        (0, 0x11D, 0),
        (1, 0x11D, 0x11D),
        (0b11, 0b11, 0b101),  # (x + 1)^2 = x^2 + 1 over GF(2)
        (0b111, 0b11, 0b1001),  # (x^2 + x + 1)(x + 1) = x^3 + 1
        (0x11D, 0x177, 0x16F63),  # m1 * m3 = the generator of the t = 2 code
    ],
)
def test_poly_mul_known_products(a: int, b: int, product: int) -> None:
    assert poly_mul(a, b) == product
    assert poly_mul(b, a) == product


@pytest.mark.parametrize(
    ("value", "modulus", "remainder"),
    [
        (0, 0b10011, 0),
        (0b1111, 0b10011, 0b1111),  # already shorter than the modulus
        (0b10000, 0b10011, 0b0011),  # x^4 = x + 1 mod x^4 + x + 1
        (0x11D, 0x11D, 0),
        (1 << 8, 0x11D, 0x1D),  # x^8 = x^4 + x^3 + x^2 + 1
        (1 << 16, 0x16F63, 0x6F63),
    ],
)
def test_poly_mod_known_remainders(value: int, modulus: int, remainder: int) -> None:
    assert poly_mod(value, modulus) == remainder


@settings(max_examples=200, deadline=None)
@given(
    quotient=st.integers(0, (1 << 80) - 1),
    modulus=st.integers(1, (1 << 33) - 1),
    rest=st.integers(0, (1 << 33) - 1),
)
def test_poly_mod_is_the_division_remainder(quotient: int, modulus: int, rest: int) -> None:
    rest &= (1 << degree(modulus)) - 1  # deg(rest) < deg(modulus)
    value = poly_mul(quotient, modulus) ^ rest
    assert poly_mod(value, modulus) == rest
    assert degree(poly_mod(value, modulus)) < degree(modulus) or degree(modulus) == 0


@settings(max_examples=100, deadline=None)
@given(a=st.integers(0, 1 << 40), b=st.integers(0, 1 << 40), c=st.integers(0, 1 << 40))
def test_poly_mul_is_a_commutative_ring_product(a: int, b: int, c: int) -> None:
    assert poly_mul(a, b) == poly_mul(b, a)
    assert poly_mul(a, b ^ c) == poly_mul(a, b) ^ poly_mul(a, c)
    assert poly_mul(poly_mul(a, b), c) == poly_mul(a, poly_mul(b, c))
    if a and b:
        assert degree(poly_mul(a, b)) == degree(a) + degree(b)


# --- GF(2^8) ------------------------------------------------------------------------------


def test_alpha_has_order_255() -> None:
    assert F.order == 255
    assert F.pow_alpha(0) == 1
    assert F.pow_alpha(255) == 1
    assert F.pow_alpha(1) == 0b10
    powers = [F.pow_alpha(i) for i in range(255)]
    assert sorted(powers) == list(range(1, 256))  # alpha generates every non-zero element
    assert 1 not in powers[1:]


def test_exp_and_log_are_inverse() -> None:
    for a in range(1, 256):
        assert F.exp[F.log[a]] == a
    for i in range(255):
        assert F.log[F.exp[i]] == i
        assert F.exp[i + 255] == F.exp[i]  # the doubled table used by mul


def test_exp_table_follows_the_primitive_polynomial() -> None:
    x = 1
    for i in range(255):
        assert F.exp[i] == x
        x = slow_mul(x, 2)


def test_mul_matches_schoolbook_multiplication_for_all_pairs() -> None:
    for a in range(256):
        for b in range(256):
            assert F.mul(a, b) == slow_mul(a, b), (a, b)


def test_div_inverts_mul_for_all_pairs() -> None:
    for a in range(256):
        for b in range(1, 256):
            q = F.div(a, b)
            assert F.mul(q, b) == a, (a, b)
            if a:
                assert F.div(b, a) == F.div(1, q)


def test_div_by_zero_raises() -> None:
    with pytest.raises(ZeroDivisionError):
        F.div(5, 0)
    with pytest.raises(ZeroDivisionError):
        F.div(0, 0)


@pytest.mark.parametrize("e", [-1, -254, -255, -1000, 256, 1000, 123456789])
def test_pow_alpha_any_integer_exponent(e: int) -> None:
    assert F.pow_alpha(e) == F.pow_alpha(e % 255)
    assert F.mul(F.pow_alpha(e), F.pow_alpha(-e)) == 1


#: Minimal polynomials of alpha^e for x^8 + x^4 + x^3 + x^2 + 1 (Lin & Costello, App. B,
#: octal 435, 567, 763, 551, 675; 23 for the order-15 elements, 37 order 5, 7 order 3).
KNOWN_MINIMAL = {
    0: 0b11,
    1: 0x11D,
    3: 0x177,
    5: 0x1F3,
    7: 0x169,
    9: 0x1BD,
    17: 0o23,
    51: 0o37,
    85: 0o7,
}


@pytest.mark.parametrize(("e", "poly"), sorted(KNOWN_MINIMAL.items()))
def test_minimal_polynomial_known_values(e: int, poly: int) -> None:
    assert F.minimal_poly(e) == poly
    assert evaluate(poly, F.pow_alpha(e)) == 0


def test_generator_of_the_default_code_is_m1_times_m3() -> None:
    assert poly_mul(F.minimal_poly(1), F.minimal_poly(3)) == 0x16F63


def cyclotomic_coset(e: int) -> set[int]:
    return {(e << j) % 255 for j in range(8)}


def test_minimal_polynomials_against_brute_force() -> None:
    """For every coset: the lowest-degree binary polynomial with alpha^e as a root."""
    seen: set[int] = set()
    for e in range(255):
        if e in seen:
            continue
        coset = cyclotomic_coset(e)
        seen |= coset
        root = F.pow_alpha(e)
        brute = next(p for p in range(2, 1 << 9) if evaluate(p, root) == 0)
        assert F.minimal_poly(e) == brute, e
        assert degree(brute) == len(coset)
        for c in coset:  # conjugates share the minimal polynomial
            assert F.minimal_poly(c) == brute
            assert evaluate(brute, F.pow_alpha(c)) == 0


@pytest.mark.parametrize(("m", "poly"), [(3, 0b1011), (4, 0b10011), (5, 0b100101), (8, 0x12B)])
def test_other_primitive_polynomials_build_a_field(m: int, poly: int) -> None:
    field = GF2m(m, poly)
    assert field.order == (1 << m) - 1
    assert sorted(field.exp[: field.order]) == list(range(1, 1 << m))


@pytest.mark.parametrize(
    ("m", "poly", "text"),
    [
        (8, 0x1D, "degree"),  # degree 4, not 8
        (4, 0x11D, "degree"),
        (8, 0x11B, "not primitive: alpha has order 51"),  # AES polynomial: irreducible only
        (8, 0x101, "not primitive"),  # (x + 1)^8
        (8, 0x100, "not primitive"),  # x^8
        (4, 0b11111, "not primitive"),  # x^4 + x^3 + x^2 + x + 1, alpha has order 5
    ],
)
def test_non_primitive_polynomials_are_refused(m: int, poly: int, text: str) -> None:
    with pytest.raises(ValueError, match=text):
        GF2m(m, poly)


# --- ChunkedRemainder ---------------------------------------------------------------------


@settings(max_examples=150, deadline=None)
@given(
    modulus=st.integers(2, (1 << 33) - 1),
    width=st.integers(1, 100),
    shift=st.integers(0, 40),
    data=st.data(),
)
def test_chunked_remainder_equals_bit_serial(
    modulus: int, width: int, shift: int, data: st.DataObject
) -> None:
    rem = ChunkedRemainder(modulus, width=width, shift=shift)
    assert len(rem.tables) == (width + 7) // 8
    assert all(len(t) == 256 for t in rem.tables)
    values = data.draw(st.lists(st.integers(0, (1 << width) - 1), min_size=1, max_size=20))
    for value in [0, (1 << width) - 1, 1 << (width - 1), *values]:
        assert rem(value) == poly_mod(value << shift, modulus), (value, width, shift)


@pytest.mark.parametrize(
    ("modulus", "width", "shift"),
    [(0b10011, 52, 4), (0x16F63, 56, 16), (0x16F63, 72, 0), (0x1EE5B42FD, 88, 0), (0x11D, 7, 3)],
)
def test_chunked_remainder_codec_shapes(
    rng: random.Random, modulus: int, width: int, shift: int
) -> None:
    rem = ChunkedRemainder(modulus, width=width, shift=shift)
    assert (rem.modulus, rem.width, rem.shift) == (modulus, width, shift)
    for _ in range(500):
        a, b = rng.getrandbits(width), rng.getrandbits(width)
        assert rem(a) == poly_mod(a << shift, modulus)
        assert rem(a ^ b) == rem(a) ^ rem(b)  # linear, which is what the tables rely on
    for i in range(width):  # every unit vector
        assert rem(1 << i) == poly_mod(1 << (i + shift), modulus)
