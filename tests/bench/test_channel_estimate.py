"""Issue 20's channel test: at emulated BER 0.005, 0.01 and 0.02, after 200 acknowledged frames
through the simulator's emulated channel and onboard agent, the estimate's 95 % interval holds
the true BER (over 20 seeded runs each: a 95 % interval misses about one run in twenty)."""

from __future__ import annotations

import io
from dataclasses import replace

import pytest

from bench import channel_estimate as bench
from sim.simulation import SimConfig, Simulation
from station.channel_estimate import FrameEvidence, evidence_of


@pytest.mark.parametrize("ber", bench.BERS)
def test_after_200_acknowledged_frames_the_interval_holds_the_emulated_ber(ber: float) -> None:
    runs = bench.coverage(ber, runs=20, frames=200)
    assert [r.seed for r in runs] == list(range(20))
    for r in runs:
        assert r.counts.frames == 200 and r.estimate.frames == 200
        assert r.estimate.low <= r.estimate.ber <= r.estimate.high
    covered = sum(r.covered for r in runs)
    # at a true 95 %, 17 or more of 20 runs hold it with probability 0.984
    assert covered >= 17, [(r.seed, r.estimate) for r in runs if not r.covered]
    mean = sum(r.estimate.ber for r in runs) / len(runs)
    assert mean == pytest.approx(ber, rel=0.1)


def test_every_simulated_acknowledgement_is_evidence_and_the_channel_flipped_its_bits() -> None:
    """The simulator's acknowledgements carry the channel's own count of flipped bits (all
    100): a decoded frame's corrected + sync errors never exceed it (the guard bits are the
    rest), and frames with none flipped decode clean."""
    sim = Simulation(SimConfig(seed=3))
    sim.channel.set_config(replace(sim.channel.config, ber=0.02))
    acks = []
    for _ in range(200):
        sim.submit_frame(bench.FRAME.to_bytes())
        sim.run_until(sim.t_s + bench.FRAME_SPACING_S)
        acks += sim.take_missions()
    assert len(acks) == 200
    for ack in acks:
        evidence = evidence_of(ack)
        assert evidence is not None
        flipped = ack["channel_flipped_bits"]
        if evidence.decoded:
            assert evidence.codeword_errors is not None and evidence.sync_errors is not None
            assert evidence.codeword_errors + evidence.sync_errors <= flipped
        else:
            assert flipped >= 3
        if flipped == 0:
            assert evidence == FrameEvidence(True, 0, 0)


def test_quick_run_prints_a_row_per_ber() -> None:
    out = io.StringIO()
    assert bench.run(out, quick=True) == 0
    lines = out.getvalue().splitlines()
    for ber in bench.BERS:
        row = next(ln for ln in lines if ln.startswith(f"{ber:g} "))
        covered, runs = (int(x) for x in row.split()[1].split("/"))
        assert runs == 5 and 0 <= covered <= 5
