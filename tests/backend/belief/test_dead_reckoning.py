"""Dead reckoning in training: the simulated vehicle flies a circle (then a lawnmower), its
telemetry stops mid-pattern (the bridge stops publishing pose and status: the vehicle goes
quiet, the acknowledgements would still come), and for 60 s of simulated time the believed
position stays within its own ``sigma_m`` of the simulator's true position, its source
``dead_reckoning``. The simulator runs at 50x, so a minute takes about a second."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import pytest
from fastapi.testclient import TestClient

from backend.belief.estimate import estimate
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    MakeClient,
    console_of,
    send,
    wait_state,
    wait_until,
)

pytestmark = pytest.mark.training

LAWNMOWER: dict[str, Any] = {
    "speed": 0.18,
    "depth": 3,
    "sweep_length": 20,
    "lane_spacing": 3,
    "laps": 4,
}
#: Simulated seconds without telemetry the belief is checked over.
WINDOW_S = 60.0


def _quiet(client: TestClient, monkeypatch: pytest.MonkeyPatch) -> None:
    """The vehicle stops publishing its pose and status."""
    bridge = console_of(client).bridge
    assert bridge is not None
    monkeypatch.setattr(bridge, "_publish_pose", lambda: None)
    monkeypatch.setattr(bridge, "_publish_status", lambda: None)


class Sample(NamedTuple):
    t_s: float  # the simulator's clock
    error_m: float  # horizontal distance from the simulator's true position
    sigma_m: float
    source: str
    fix_t_s: float  # the last fix's time (the simulator's clock)


def _sample(client: TestClient) -> Sample:
    """The belief and the simulator at one instant: read together on the app's event loop
    (the simulator does not move between)."""
    console = console_of(client)

    def read() -> Sample:
        assert console.beliefs is not None and console.sim is not None
        assert console.hub.known_pose is not None
        b = estimate(console.beliefs.default.evidence())
        v, p = console.sim.vehicle, b.position
        sigma = p.sigma_m if p.sigma_m is not None else math.nan
        error = math.hypot(p.x_m - v.x, p.y_m - v.y)
        return Sample(console.sim.t_s, error, sigma, p.source, console.hub.known_pose["t_s"] or 0)

    out: Sample = client.portal.call(read)  # type: ignore[union-attr]
    return out


def _sample_after(client: TestClient, t_s: float) -> Sample:
    """The first sample at or after the simulator's time ``t_s``."""
    return wait_until(lambda: (s := _sample(client)).t_s >= t_s and s, what=f"sim at {t_s} s")


def _fly_then_go_quiet(
    client: TestClient,
    monkeypatch: pytest.MonkeyPatch,
    pattern: str,
    params: dict[str, Any],
    quiet_at_s: float,
) -> list[Sample]:
    r = client.put("/api/training/channel", json={"ber": 0.0, "loss": 0.0}, headers=AUTH)
    assert r.status_code == 200, r.text
    wait_until(lambda: client.get("/api/vehicle").json()["pose"], what="the first pose")
    cmd = wait_state(client, send(client, pattern, params)["id"])
    assert cmd["state"] == "acknowledged", cmd
    sim = console_of(client).sim
    assert sim is not None
    wait_until(lambda: sim.t_s >= quiet_at_s, what=f"{quiet_at_s} s of {pattern}")
    _quiet(client, monkeypatch)
    # A pose already on its way when the vehicle went quiet can still arrive (a loaded machine
    # lags seconds behind the simulator): the window starts again from the newest fix, a few
    # times at most, since nothing new is published.
    for _ in range(3):
        first = wait_until(
            lambda: (s := _sample(client)).source == "dead_reckoning" and s, what="dead reckoning"
        )
        samples = [first]
        while samples[-1].t_s - first.fix_t_s < WINDOW_S:  # one sample a simulated second
            samples.append(_sample_after(client, samples[-1].t_s + 1.0))
            if samples[-1].fix_t_s != first.fix_t_s:
                break  # a late fix: start again from it
        else:
            break
    assert {s.fix_t_s for s in samples} == {first.fix_t_s}  # no telemetry came since
    served = client.get("/api/vehicle").json()["belief"]["position"]
    assert served["source"] == "dead_reckoning" and served["age_s"] > 0, served
    return samples


def _check(samples: list[Sample]) -> None:
    assert len(samples) >= 10, samples
    for s in samples:
        assert s.source == "dead_reckoning", s
        assert s.error_m <= s.sigma_m, f"{s.t_s - s.fix_t_s:.1f} s after the fix: {s}"
    # the uncertainty grows with time without telemetry
    assert samples[-1].sigma_m > samples[0].sigma_m
    worst = max(s.error_m / s.sigma_m for s in samples)
    print(f"{len(samples)} samples, worst error/sigma {worst:.2f}")


def test_a_quiet_circle_stays_within_its_sigma(
    make_client: MakeClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    client = make_client(viewer=True)
    _check(_fly_then_go_quiet(client, monkeypatch, "circle", CIRCLE, 150.0))
    # the 3D view draws the believed position with its ring (pushed every second)
    viewer = console_of(client).viewer
    assert viewer is not None
    wait_until(lambda: viewer.node("/belief/ring") is not None, what="the belief's ring")
    assert viewer.node("/belief/label").text.startswith("believed (dead reckoning, +-")  # type: ignore[union-attr]


def test_a_quiet_lawnmower_stays_within_its_sigma(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    # quiet before the end of the first lane: the minute holds two corners
    _check(_fly_then_go_quiet(client, monkeypatch, "lawnmower", LAWNMOWER, 90.0))
