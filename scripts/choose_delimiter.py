"""Rank all 256 delimiters by how well preamble + delimiter resists false frame sync.

The sync word is the 16-bit alternating preamble followed by the 8-bit delimiter. The
receiver compares every 24-bit window of the stream with it. Because the preamble has period
2, a window shifted by an even number of bits still matches the preamble part, so only the
delimiter can make shifted windows differ. For each candidate this prints:

* ``min_shift``: the fewest mismatches between the sync word and a copy of itself shifted by
  1..15 bits, counting only bits known in both (the rest of the stream is unknown);
* ``min_lead``: the fewest mismatches of windows that start 1..40 bits early when the frame
  is preceded by alternating bits, zeros or ones (an idle line or a preamble-like burst);
* ``min_tail``: the same for windows that start late when the codeword is all zeros or ones;
* ``sidelobes``: the sum of the shifted mismatches over shifts 1..15 (higher is better).

Six delimiters tie on the three guaranteed distances (4, 5, 5) and three of those also on the
sum; the codec takes 0x7C among them because its run of five ones is the easiest break from
the alternating preamble to spot by eye in a bit dump or on a scope trace.

Run: ``python scripts/choose_delimiter.py`` (prints the top 10; the codec uses 0x7C).
"""

from __future__ import annotations

PREAMBLE = [1, 0] * 8


def bits_of(byte: int) -> list[int]:
    return [(byte >> (7 - i)) & 1 for i in range(8)]


def mismatches(a: list[int], b: list[int]) -> int:
    return sum(x != y for x, y in zip(a, b, strict=False))


def score(delimiter: int) -> tuple[int, int, int, int]:
    sync = PREAMBLE + bits_of(delimiter)
    n = len(sync)
    shifted = [mismatches(sync[: n - s], sync[s:]) for s in range(1, 16)]
    min_shift = min(shifted)
    leads = ([1, 0] * 20, [0] * 40, [1] * 40)
    min_lead = min(
        mismatches((lead + sync)[40 - s : 40 - s + n], sync) for lead in leads for s in range(1, 41)
    )
    tails = ([0] * 40, [1] * 40)
    min_tail = min(
        mismatches((sync + tail)[s : s + n], sync) for tail in tails for s in range(1, 41)
    )
    return min_shift, min_lead, min_tail, sum(shifted)


def main() -> None:
    ranked = sorted(range(256), key=lambda d: (score(d), -d), reverse=True)
    print("delimiter  bits      min_shift  min_lead  min_tail  sidelobes")
    for d in ranked[:10]:
        s = score(d)
        print(f"0x{d:02X}       {d:08b}  {s[0]:>9}  {s[1]:>8}  {s[2]:>8}  {s[3]:>9}")


if __name__ == "__main__":
    main()
