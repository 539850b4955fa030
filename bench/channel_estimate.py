"""``nemesys bench channel_estimate``: does the online BER estimate's 95 % interval hold the
emulated channel's BER?

Each run is a fresh simulated vehicle (its seed: the run's number) whose emulated ME channel
(:mod:`sim.channel`, the training console's, only its BER changed) flips bits of every frame
the station sends; the simulator's onboard agent decodes each and acknowledges it, and the
acknowledgements feed the console's estimator (:class:`station.channel_estimate.
ChannelEstimator`) exactly as the command manager feeds it, until :data:`FRAMES` frames are
acknowledged. The table gives, per BER, how many runs' interval held the true BER (the
coverage), the mean estimate and interval, and the frames the decoder refused. The console
is not in the loop (it only forwards the acknowledgements; ``tests/backend/commands/
test_channel_estimate_console.py`` checks that path end to end): this drives 200 frames in
well under a second a run instead of minutes of rate-limited sends.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass, replace
from typing import Final, TextIO

from bench._timing import table
from codec import encode_frame
from sim.simulation import SimConfig, Simulation
from station.channel_estimate import BerEstimate, ChannelCounts, ChannelEstimator

#: The emulated BERs of the issue's test (issue 20).
BERS: Final = (0.005, 0.01, 0.02)
#: Runs per BER (seeds 0 .. RUNS - 1).
RUNS: Final = 20
#: Acknowledged frames per run.
FRAMES: Final = 200
#: Simulated time between two frames (s): the frame's 2.8 ms airtime and a few physics steps.
FRAME_SPACING_S: Final = 0.1
#: The command every frame carries (a duplicate after the first: the vehicle does not replan).
FRAME: Final = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame


@dataclass(frozen=True, slots=True)
class Run:
    """One run: the emulated BER, the seed, the estimate and the counts it rests on."""

    ber: float
    seed: int
    estimate: BerEstimate
    counts: ChannelCounts
    #: The bits the channel flipped per bit it delivered in this run (its own count).
    measured_ber: float

    @property
    def covered(self) -> bool:
        return self.estimate.low <= self.ber <= self.estimate.high


def sim_run(ber: float, seed: int, frames: int = FRAMES) -> Run:
    """``frames`` acknowledged frames through a simulated vehicle's channel at ``ber``."""
    config = SimConfig(seed=seed)
    sim = Simulation(replace(config, channel=replace(config.channel, ber=ber)))
    estimator = ChannelEstimator(min_frames=1)
    data = FRAME.to_bytes()
    while estimator.counts.frames < frames:
        sim.submit_frame(data)
        sim.run_until(sim.t_s + FRAME_SPACING_S)
        for ack in sim.take_missions():
            estimator.observe(ack)
    estimate = estimator.estimate()
    assert estimate is not None
    return Run(ber, seed, estimate, estimator.counts, sim.channel.measured_ber)


def coverage(ber: float, runs: int = RUNS, frames: int = FRAMES) -> list[Run]:
    """Runs with seeds 0 .. ``runs`` - 1 at ``ber``."""
    return [sim_run(ber, seed, frames) for seed in range(runs)]


def _g(x: float) -> str:
    return f"{x:.3g}"


def run(out: TextIO, *, quick: bool = False) -> int:
    runs = 5 if quick else RUNS
    out.write(
        f"BER estimate from {FRAMES} acknowledged frames through the simulator's emulated "
        f"channel and onboard agent: {runs} runs per BER (seeds 0-{runs - 1}), maximum "
        "likelihood with a 95 % likelihood-ratio interval\n\n"
    )
    rows = []
    for ber in BERS:
        results = coverage(ber, runs)
        covered = sum(r.covered for r in results)
        missed = ", ".join(str(r.seed) for r in results if not r.covered) or "-"
        rows.append(
            [
                f"{ber:g}",
                f"{covered}/{runs}",
                f"{100 * covered / runs:.0f} %",
                _g(statistics.mean(r.estimate.ber for r in results)),
                f"{_g(statistics.mean(r.estimate.low for r in results))}"
                f"-{_g(statistics.mean(r.estimate.high for r in results))}",
                _g(statistics.mean(r.measured_ber for r in results)),
                f"{statistics.mean(r.counts.not_decoded for r in results):.1f}",
                missed,
            ]
        )
    headers = [
        "emulated BER",
        "covered",
        "coverage",
        "mean estimate",
        "mean interval",
        "channel's own",
        "not decoded/run",
        "missed (seeds)",
    ]
    out.write(table(headers, rows) + "\n")
    out.write(
        "\n'channel's own': bits the emulated channel flipped per bit sent, over all 100 bits "
        "of the runs' frames (the realised BER, which the estimate sees through the decoder).\n"
    )
    return 0


if __name__ == "__main__":
    import sys

    raise SystemExit(run(sys.stdout))
