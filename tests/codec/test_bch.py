"""BCH codes: generators, encodings and both decoders against the galois and bchlib oracles."""

from __future__ import annotations

import itertools
import random
from typing import Any

import bchlib
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codec import CODE, UNCORRECTABLE, BCHCode, TableDecoder
from codec._bch import make_corrector
from codec._gf2 import poly_mod
from tests.codec.helpers import galois_code, galois_vectors, mask_of, random_error

T_VALUES = (1, 2, 3, 4)
CODES = {t: BCHCode(t) for t in T_VALUES}
TABLE = TableDecoder(CODE)
BCHLIB = bchlib.BCH(2, m=8)


def bchlib_decode(received: int) -> tuple[int, int]:
    """bchlib's (nerr, corrected message) for a 72-bit word: 7 data bytes + 2 ecc bytes."""
    data = bytearray((received >> 16).to_bytes(7, "big"))
    ecc = bytearray((received & 0xFFFF).to_bytes(2, "big"))
    nerr: int = BCHLIB.decode(data, ecc)
    if nerr >= 0:
        BCHLIB.correct(data, ecc)
    return nerr, int.from_bytes(data, "big")


def decoders(t: int) -> list[Any]:
    """The decoders available for the t-error code (the table decoder only for the default)."""
    return [CODES[t].decode, TABLE.decode] if t == 2 else [CODES[t].decode]


# --- generators and encodings vs galois -------------------------------------------------------


def test_vectors_file_covers_t_1_to_4() -> None:
    doc = galois_vectors()
    assert [c["t"] for c in doc["codes"]] == list(T_VALUES)
    for code in doc["codes"]:
        assert code["prim_poly"] == "0x11d"
        assert (code["m"], code["k"], code["n"]) == (8, 56, 56 + 8 * code["t"])
        assert len(code["encodings"]) == 100
        assert {d["n_errors"] for d in code["decodings"]} == set(range(code["t"] + 3))


@pytest.mark.parametrize("t", T_VALUES)
def test_generator_matches_galois(t: int) -> None:
    vectors = galois_code(t)
    code = CODES[t]
    assert code.generator_poly == int(vectors["generator_poly"], 16)
    assert (code.n, code.k, code.r, code.t, code.d, code.m) == (
        vectors["n"],
        56,
        8 * t,
        t,
        2 * t + 1,
        8,
    )
    assert repr(code) == (
        f"<BCH code [{code.n}, 56, {2 * t + 1}] over GF(2^8), t={t}, g={vectors['generator_poly']}>"
    )


def test_default_code_is_bch_72_56_t2() -> None:
    assert (CODE.n, CODE.k, CODE.t, CODE.r) == (72, 56, 2, 16)
    assert CODE.generator_poly == 0x16F63
    assert CODE.field.prim_poly == 0x11D


@pytest.mark.parametrize("t", T_VALUES)
def test_encodings_match_galois(t: int) -> None:
    code = CODES[t]
    for entry in galois_code(t)["encodings"]:
        msg, cw = int(entry["message"], 16), int(entry["codeword"], 16)
        assert code.encode(msg) == cw, entry
        assert cw >> code.r == msg  # systematic, message first
        assert poly_mod(cw, code.generator_poly) == 0
        assert code.remainder(cw) == 0
        assert code.syndromes(cw) == [0] * (2 * t)


@pytest.mark.parametrize("t", T_VALUES)
def test_decodings_match_galois(t: int) -> None:
    """Every recorded galois decoding, miscorrections and failures included."""
    code = CODES[t]
    records = galois_code(t)["decodings"]
    outcomes = set()
    for decode in decoders(t):
        for rec in records:
            received = int(rec["received"], 16)
            message, n_corrected = decode(received)
            assert n_corrected == rec["n_corrected"], rec
            if n_corrected != UNCORRECTABLE:
                assert message == int(rec["message"], 16), rec
                assert (code.encode(message) ^ received).bit_count() == n_corrected
            else:
                assert message == received >> code.r  # the uncorrected message bits
            outcomes.add((rec["n_errors"] <= t, n_corrected == UNCORRECTABLE))
    assert (False, True) in outcomes  # the vectors exercise failures too


@pytest.mark.parametrize(
    ("message", "codeword"),
    [
        (0x00000000000001, 0x000000000000016F63),
        (0x0123456789ABC0, 0x0123456789ABC0C936),
        (0xFFFFFFFFFFFFF0, 0xFFFFFFFFFFFFF05F2A),
        (0x80000000000000, 0x80000000000000BA02),
        (0x00000000000000, 0x000000000000000000),
    ],
)
def test_research_vectors(message: int, codeword: int) -> None:
    assert CODE.encode(message) == codeword
    for decode in decoders(2):
        assert decode(codeword) == (message, 0)


@pytest.mark.parametrize("message", [-1, 1 << 56, 1 << 60])
def test_encode_refuses_messages_that_do_not_fit(message: int) -> None:
    with pytest.raises(ValueError, match="56 bits"):
        CODE.encode(message)


def test_code_parameters_are_checked() -> None:
    with pytest.raises(ValueError):
        BCHCode(0)
    with pytest.raises(ValueError, match="exceeds"):
        BCHCode(31)  # r = 200: n = 256 > 255
    assert BCHCode(30).n == 248
    with pytest.raises(ValueError):
        TableDecoder(CODES[3])
    with pytest.raises(ValueError):
        TableDecoder(CODES[1])


# --- bchlib -----------------------------------------------------------------------------------


def test_bchlib_is_the_same_code() -> None:
    assert BCHLIB.m == 8
    assert BCHLIB.t == 2
    assert BCHLIB.prim_poly == 0x11D
    assert BCHLIB.ecc_bits == 16
    assert BCHLIB.ecc_bytes == 2


def test_parity_matches_bchlib(rng: random.Random) -> None:
    messages = [0, 1, (1 << 56) - 1, 1 << 55, 0x0123456789ABC0]
    messages += [rng.getrandbits(56) for _ in range(400)]
    for msg in messages:
        ecc = BCHLIB.encode(msg.to_bytes(7, "big"))
        assert CODE.encode(msg) == (msg << 16) | int.from_bytes(ecc, "big"), hex(msg)


# --- correction within t ----------------------------------------------------------------------


def test_every_single_error_is_corrected(rng: random.Random) -> None:
    messages = [0, (1 << 56) - 1] + [rng.getrandbits(56) for _ in range(40)]
    for msg in messages:
        cw = CODE.encode(msg)
        for i in range(72):
            received = cw ^ (1 << i)
            assert CODE.decode(received) == (msg, 1), (hex(msg), i)
            assert TABLE.decode(received) == (msg, 1), (hex(msg), i)


def test_every_double_error_is_corrected_exhaustively() -> None:
    msg = 0x0123456789ABC0
    cw = CODE.encode(msg)
    pairs = list(itertools.combinations(range(72), 2))
    assert len(pairs) == 2556
    for i, j in pairs:
        received = cw ^ (1 << i) ^ (1 << j)
        assert TABLE.decode(received) == (msg, 2), (i, j)
        assert CODE.decode(received) == (msg, 2), (i, j)


def test_sampled_double_errors_are_corrected(rng: random.Random) -> None:
    for _ in range(3000):
        msg = rng.getrandbits(56)
        received = CODE.encode(msg) ^ random_error(rng, 72, 2)
        assert CODE.decode(received) == (msg, 2)
        assert TABLE.decode(received) == (msg, 2)


def test_table_decoder_holds_every_correctable_pattern() -> None:
    patterns = TABLE.error_patterns
    assert len(patterns) == 72 + 2556
    assert sorted(e.bit_count() for e in patterns.values()).count(1) == 72
    for syndrome, error in patterns.items():
        assert syndrome == CODE.remainder(error) != 0


@settings(max_examples=200, deadline=None)
@given(
    t=st.sampled_from(T_VALUES),
    message=st.integers(0, (1 << 56) - 1),
    data=st.data(),
)
def test_bm_corrects_up_to_t_errors_for_every_t(t: int, message: int, data: st.DataObject) -> None:
    code = CODES[t]
    positions = data.draw(st.sets(st.integers(0, code.n - 1), max_size=t), label="errors")
    received = code.encode(message) ^ mask_of(positions)
    assert code.decode(received) == (message, len(positions))
    # Bits above the codeword length are ignored by the BM decoder.
    assert code.decode(received | (1 << code.n)) == (message, len(positions))


# --- beyond t: both decoders and bchlib agree ---------------------------------------------------


@pytest.mark.parametrize("weight", [3, 4, 5])
def test_beyond_t_outcomes_agree_with_bchlib(rng: random.Random, weight: int) -> None:
    seen = {"failed": 0, "miscorrected": 0}
    for _ in range(1500):
        msg = rng.getrandbits(56)
        received = CODE.encode(msg) ^ random_error(rng, 72, weight)
        bm = CODE.decode(received)
        assert TABLE.decode(received) == bm, hex(received)
        nerr, bchlib_message = bchlib_decode(received)
        if bm[1] == UNCORRECTABLE:
            assert nerr == -1, hex(received)
            assert bm[0] == received >> 16
            seen["failed"] += 1
        else:  # a miscorrection to the nearest other codeword, within 2 bits
            assert nerr == bm[1], hex(received)
            assert bchlib_message == bm[0], hex(received)
            assert bm[0] != msg
            assert (CODE.encode(bm[0]) ^ received).bit_count() == bm[1] <= 2
            seen["miscorrected"] += 1
    assert seen["failed"] > 1000
    assert seen["miscorrected"] > 0


def test_random_words_decode_identically(rng: random.Random) -> None:
    """Random 72-bit words: the table and BM decoders are the same bounded-distance decoder."""
    counts = {-1: 0, 0: 0, 1: 0, 2: 0}
    for _ in range(20_000):
        received = rng.getrandbits(72)
        bm = CODE.decode(received)
        assert TABLE.decode(received) == bm, hex(received)
        counts[bm[1]] += 1
        if bm[1] != UNCORRECTABLE:
            assert (CODE.encode(bm[0]) ^ received).bit_count() == bm[1]
    # About (1 + 72 + 2556) / 65536 = 4 % of random words are within 2 bits of a codeword.
    assert 500 < counts[1] + counts[2] < 1200
    for received in (0, (1 << 72) - 1, 0xAAAAAAAAAAAAAAAAAA, 0x555555555555555555):
        assert TABLE.decode(received) == CODE.decode(received)
        assert TABLE.decode_bytes(received.to_bytes(9, "big")) == CODE.decode(received)


def test_decode_bytes_matches_decode(rng: random.Random) -> None:
    for weight in range(5):
        for _ in range(300):
            received = CODE.encode(rng.getrandbits(56)) ^ random_error(rng, 72, weight)
            assert TABLE.decode_bytes(received.to_bytes(9, "big")) == TABLE.decode(received)


# --- the algebra ---------------------------------------------------------------------------------


@pytest.mark.parametrize("t", T_VALUES)
def test_syndromes_of_single_errors(t: int) -> None:
    code = CODES[t]
    f = code.field
    for i in (0, 1, 7, code.n - 1):
        assert code.syndromes(1 << i) == [f.pow_alpha(i * j) for j in range(1, 2 * t + 1)]


@pytest.mark.parametrize("t", T_VALUES)
def test_error_locator_and_chien_search_find_the_errors(rng: random.Random, t: int) -> None:
    code = CODES[t]
    for weight in range(1, t + 1):
        for _ in range(30):
            positions = sorted(rng.sample(range(code.n), weight))
            received = code.encode(rng.getrandbits(56)) ^ mask_of(positions)
            lam = code.error_locator(code.syndromes(received))
            assert len(lam) - 1 == weight
            assert lam[0] == 1
            assert code.chien_search(lam) == positions


# --- memory: shared byte tables, correction table built on first use -------------------------


def test_remainder_shares_the_parity_tables() -> None:
    code = BCHCode(t=2, k=56)
    parity, remainder = code.parity_tables, code.remainder_tables
    assert len(parity) == 7 and len(remainder) == 9
    assert all(r is p for r, p in zip(remainder, parity, strict=False))  # message bytes
    assert list(remainder[7]) == [b << 8 for b in range(256)]  # parity bytes: already reduced
    assert list(remainder[8]) == list(range(256))
    assert all(isinstance(t, memoryview) for t in remainder)  # 16-bit values, packed
    for j, table in enumerate(reversed(remainder)):
        assert table[1] == poly_mod(1 << (8 * j), code.generator_poly)


def test_table_decoder_corrects_without_its_error_dictionary(rng: random.Random) -> None:
    """Decoding words with errors never builds the 2628-entry dictionary (~300 KiB): the
    closed-form corrector does the work; ``error_patterns`` builds it only when asked."""
    decoder = TableDecoder(BCHCode(t=2, k=56))
    msg = rng.getrandbits(56)
    cw = CODE.encode(msg)
    assert decoder.decode(cw) == (msg, 0)
    assert decoder.decode_bytes(cw.to_bytes(9, "big")) == (msg, 0)
    assert decoder.decode_bytes((cw ^ 0b11 << 20).to_bytes(9, "big")) == (msg, 2)
    assert decoder.decode(cw ^ 1 << 71) == (msg, 1)
    assert decoder.decode(cw ^ 0b111) == CODE.decode(cw ^ 0b111)
    assert decoder._errors is None
    assert len(decoder.error_patterns) == 2628
    assert decoder._errors is not None


@pytest.mark.parametrize("t", [1, 2])
def test_closed_form_corrector_equals_the_syndrome_table_on_every_syndrome(t: int) -> None:
    """Every possible remainder: the same error pattern as the table of all correctable
    patterns, and ``None`` exactly where the table has no entry (bounded distance)."""
    code = BCHCode(t=t, k=72 - 8 * t)
    decoder = TableDecoder(code)
    table = dict(decoder.error_patterns)
    found = {syndrome: decoder.correct(syndrome) for syndrome in range(1, 1 << code.r)}
    assert {s: e for s, e in found.items() if e is not None} == table
    assert sum(e is None for e in found.values()) == (1 << code.r) - 1 - len(table)


def test_closed_form_corrector_refuses_codes_it_does_not_handle() -> None:
    with pytest.raises(ValueError, match="t <= 2"):
        make_corrector(CODES[3])


def test_table_decoder_for_the_single_error_72_64_code(rng: random.Random) -> None:
    code = BCHCode(t=1, k=64)
    assert (code.n, code.r) == (72, 8)
    decoder = TableDecoder(code)
    for _ in range(200):
        msg = rng.getrandbits(64)
        cw = code.encode(msg)
        for received in (cw, cw ^ 1 << rng.randrange(72), cw ^ random_error(rng, 72, 2)):
            expected = code.decode(received)
            assert decoder.decode(received) == expected
            assert decoder.decode_bytes(received.to_bytes(9, "big")) == expected


def test_written_out_decoders_agree_with_the_corrector_on_every_remainder() -> None:
    """The table decoder writes the closed form out (no call): for every non-zero remainder,
    the word that is that remainder (message 0, parity bits = the remainder) decodes to what
    :meth:`TableDecoder.correct` says, through both entry points."""
    for syndrome in range(1, 1 << CODE.r):
        error = TABLE.correct(syndrome)
        expected = (0, UNCORRECTABLE) if error is None else ((syndrome ^ error) >> 16, 2)
        if error is not None:
            expected = (expected[0], error.bit_count())
        assert TABLE.decode_bytes(syndrome.to_bytes(9, "big")) == expected, syndrome
        assert TABLE.decode(syndrome) == expected, syndrome


def test_message_tables_are_the_codes_remainder_tables() -> None:
    """The frame's decoder shares its message tables with the receiver's CRC check (bits 16
    and up); bits 0-15 are the code's remainder tables, and other tables are refused."""
    from codec import FAST_DECODER

    for mine, reference in zip(FAST_DECODER.message_tables, CODE.remainder_tables, strict=False):
        assert [v & 0xFFFF for v in mine] == list(reference)
    assert any(max(t) >> 16 for t in FAST_DECODER.message_tables)  # the CRC check's bits
    assert TableDecoder(CODE).message_tables == tuple(tuple(t) for t in CODE.remainder_tables[:7])
    wrong = [list(t) for t in TableDecoder(CODE).message_tables]
    wrong[3][5] ^= 1
    with pytest.raises(ValueError, match="not the code's remainder tables"):
        TableDecoder(CODE, wrong)
