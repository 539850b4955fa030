"""POST /api/predict: the twin's track for a command from the vehicle's state now."""

from __future__ import annotations

import copy
import math
import threading
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.api.predict import _gate
from backend.authoring.predict import MAX_POINTS, QUEUE, WORKER_NICE, decimate
from backend.chart.geo import ned_to_geodetic
from bench._server import start_console
from codec import encode_frame
from tests.backend.conftest import AUTH, CIRCLE, MakeClient, console_of, send, wait_until
from vehicle_contract.codes import Mode

LAWNMOWER = {"speed": 0.18, "depth": 3, "sweep_length": 10, "lane_spacing": 2, "laps": 1}
#: Largest distance between the prediction and the full simulation at the same instant (m).
TOLERANCE_M = 0.25


def _paused_mid_circle(client: TestClient) -> Any:
    """The training vehicle flying a circle for 60 s, then paused, once the console's
    telemetry shows exactly the paused state. Returns the simulator."""
    console = console_of(client)
    sim = console.sim
    assert sim is not None
    send(client, "circle", CIRCLE)
    wait_until(lambda: sim.t_s > 60.0, 30.0, what="a minute on the circle")
    r = client.put("/api/training/time_scale", json={"time_scale": 0}, headers=AUTH)
    assert r.status_code == 200, r.text

    def paused_state_shown() -> bool:
        # the pose's stamp is whole nanoseconds (sec + nanosec): equal to the simulator's
        # clock only to within a nanosecond, never exactly in general
        pose_t = (console.hub.pose or {}).get("t_s")
        status_t = (console.hub.status or {}).get("t_s")
        return (
            isinstance(pose_t, float)
            and isinstance(status_t, float)
            and abs(pose_t - sim.t_s) < 1e-6
            and abs(status_t - sim.t_s) < 1e-6
            and console.commands is not None
            and console.commands.mirror is not None
        )

    wait_until(paused_state_shown, what="telemetry of the paused vehicle")
    return sim


@pytest.mark.parametrize(
    ("pattern", "params"),
    [("lawnmower", LAWNMOWER), ("circle", {**CIRCLE, "radius": 4})],
)
@pytest.mark.training
def test_the_prediction_is_a_full_simulation_from_the_same_state(
    client: TestClient, pattern: str, params: dict[str, Any]
) -> None:
    """The reference is the training vehicle itself: a deep copy of the paused simulator
    (every state variable, its plan, its random generators), sent the same frame and run on.

    The prediction starts from what the console knows (the reported pose, speed through the
    water, the clock, the mirrored plan, the battery): not the sway and yaw rates, the roll,
    the thrusters' lag, the autopilot's filters or the depth sensor's noise generator. Those
    decay within seconds of a retask and differ by centimetres (3 cm measured here over both
    the lawnmower and the circle). 0.25 m is a sixth of guidance's 1.5 m lookahead and under
    half the 0.6 m corners are cut by: a difference the chart could not show, while a wrong
    start (another anchor, a lost join, the wrong speed) would be off by metres.
    """
    sim = _paused_mid_circle(client)
    assert client.portal is not None
    reference = client.portal.call(copy.deepcopy, sim)
    r = client.post("/api/predict", json={"pattern": pattern, "params": params})
    assert r.status_code == 200, r.text
    pred = r.json()
    assert pred["outcome"] == "accepted"
    reference.submit_frame(encode_frame(pattern, params).frame.to_bytes())
    t0 = reference.t_s
    done: float | None = None
    worst = 0.0
    for t, x, y, z in zip(pred["t_s"], pred["x_m"], pred["y_m"], pred["z_m"], strict=True):
        while reference.t_s < t0 + t - 1e-9:
            reference.run_until(reference.t_s + 0.1)
            if done is None and reference.acks and reference.mode is Mode.HOLDING:
                done = reference.t_s - t0
        v = reference.vehicle
        worst = max(worst, math.dist((x, y, z), (v.x, v.y, v.z)))
    assert worst <= TOLERANCE_M
    assert pred["max_deviation_m"] < 1.0
    if pattern == "lawnmower":
        assert pred["completes"] is True and done is not None
        assert pred["duration_s"] == pytest.approx(done, abs=0.5)  # from arrival, ~0.1 s later
        assert pred["planned_duration_s"] > pred["duration_s"]  # corners are cut
        assert pred["repeats"] is False
    else:
        # a repeating pattern: the join and one lap, by the reference's own completion rule
        assert pred["repeats"] is True and pred["completes"] is True
        lap_done = reference.completion.done_s
        assert lap_done is not None and pred["duration_s"] is not None
        assert pred["duration_s"] == pytest.approx(lap_done - t0, abs=0.5)
        assert pred["planned_duration_s"] == pytest.approx(pred["estimate_duration_s"], rel=0.2)


@pytest.mark.slow  # a full-horizon twin run, ~1 s
def test_the_horizon_is_bounded(client: TestClient) -> None:
    body = {"pattern": "circle", "params": CIRCLE}
    pred = client.post("/api/predict", json=body).json()
    assert pred["horizon_s"] == pytest.approx(600.0)
    assert len(pred["t_s"]) <= MAX_POINTS and pred["t_s"][-1] == pytest.approx(600.0)
    assert pred["t_s"] == sorted(pred["t_s"])
    short = client.post("/api/predict?horizon_s=30", json=body).json()
    assert short["horizon_s"] == pytest.approx(30.0) and short["t_s"][-1] == pytest.approx(30.0)
    # a horizon between two physics steps (20 ms) ends at the last whole step
    odd = client.post("/api/predict?horizon_s=20.129264947453024", json=body).json()
    assert odd["horizon_s"] == pytest.approx(20.12, abs=0.011)
    surface = client.post("/api/predict?horizon_s=0.005", json={"pattern": "surface"}).json()
    assert surface["horizon_s"] == 0.0 and surface["t_s"] == [0.0]
    hover = {"pattern": "hover", "params": {"duration": 20, "depth": 2, "heading": 0}}
    held = client.post("/api/predict", json=hover).json()
    assert held["completes"] is True and held["duration_s"] == pytest.approx(20.0, abs=0.2)
    assert held["horizon_s"] == pytest.approx(30.0, abs=0.5)  # completion + the 10 s margin


def test_decimation_keeps_the_ends_and_the_cap() -> None:
    assert decimate(5) == [0, 1, 2, 3, 4]
    kept = decimate(6001)
    assert len(kept) <= MAX_POINTS and kept[0] == 0 and kept[-1] == 6000


def test_busy_predictions_get_503_with_retry_after(client: TestClient) -> None:
    gate = _gate(console_of(client))
    body = {"pattern": "hover", "params": {"duration": 5, "depth": 2, "heading": 0}}
    answers: list[int] = []
    with gate.slot():  # a prediction runs (this test holds its place)
        waiting = [
            threading.Thread(
                target=lambda: answers.append(client.post("/api/predict", json=body).status_code)
            )
            for _ in range(QUEUE)
        ]
        for t in waiting:
            t.start()
        wait_until(lambda: gate.admitted == 1 + QUEUE, what="the queue full")
        r = client.post("/api/predict", json=body)
        assert r.status_code == 503
        assert int(r.headers["retry-after"]) >= 1
        assert "retry" in r.json()["detail"]
        assert answers == []  # the queued ones still wait
    for t in waiting:
        t.join(60)
    assert answers == [200] * QUEUE
    assert client.post("/api/predict", json=body).status_code == 200


@pytest.mark.parametrize(
    ("url", "body", "loc"),
    [
        ("/api/predict", {"params": {}}, ["body", "pattern"]),
        ("/api/predict", {"pattern": "zigzag", "params": {}}, ["body", "pattern"]),
        ("/api/predict", {"pattern": "circle", "params": {**CIRCLE, "speed": 9}}, None),
        ("/api/predict", {"pattern": "circle", "params": CIRCLE, "x": 1}, ["body", "x"]),
        ("/api/predict?horizon_s=0", {"pattern": "circle", "params": CIRCLE}, None),
        ("/api/predict?horizon_s=601", {"pattern": "circle", "params": CIRCLE}, None),
    ],
)
def test_bad_input_is_422_naming_the_field(
    client: TestClient, url: str, body: dict[str, Any], loc: list[str] | None
) -> None:
    r = client.post(url, json=body)
    assert r.status_code == 422, r.text
    got = r.json()["detail"][0]["loc"]
    if loc is not None:
        assert got == loc
    elif "horizon_s" in url:
        assert got == ["query", "horizon_s"]
    else:
        assert got == ["body", "params", "speed"]


@pytest.mark.training
def test_lat_lon_come_from_the_datum_through_backend_geo(client: TestClient) -> None:
    datum = console_of(client).datum
    assert datum is not None  # training's documented site
    pred = client.post("/api/predict?horizon_s=60", json={"pattern": "circle", "params": CIRCLE})
    doc = pred.json()
    lat, lon = ned_to_geodetic(datum, doc["x_m"], doc["y_m"])
    assert doc["lat_deg"] == pytest.approx(list(lat), abs=1e-12)
    assert doc["lon_deg"] == pytest.approx(list(lon), abs=1e-12)
    assert len(doc["lat_deg"]) == len(doc["x_m"])


def test_a_real_vehicle_runs_the_twin_from_its_last_pose_and_says_so(
    make_client: MakeClient,
) -> None:
    client = make_client(target="ws://127.0.0.1:9")  # nothing there: no pose, no datum
    r = client.post("/api/predict?horizon_s=60", json={"pattern": "circle", "params": CIRCLE})
    assert r.status_code == 200, r.text
    doc = r.json()
    assert doc["lat_deg"] is None and doc["lon_deg"] is None
    assert any("no simulator" in a for a in doc["assumptions"])
    assert any("no water current" in a for a in doc["assumptions"])
    assert doc["x_m"][0] == 0.0 and doc["outcome"] == "accepted"


def _children(pid: int) -> set[int]:
    """Processes whose parent is ``pid`` (from /proc)."""
    out = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.add(int(stat.parent.name))
    return out


def _nice(pid: int) -> int:
    """A process's nice value (field 19 of /proc/<pid>/stat)."""
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[16])


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.slow  # starts and ends the twin's worker process, ~1.3 s
@pytest.mark.parametrize("ending", ["stop", "kill"])
def test_the_twin_worker_never_outlives_the_console(tmp_path: Path, ending: str) -> None:
    """Stopped (SIGTERM, the lifespan closes it) or killed (SIGKILL, no shutdown at all): the
    prediction's worker process exits with the console, never left behind as an orphan."""
    env = {"NEMESYS_DB_PATH": str(tmp_path / "log.sqlite3")}
    console = start_console(tmp_path / "console.log", "predict-test-token-0123456789", env=env)
    try:
        before = _children(console.pid)
        with console.client(timeout_s=60) as http:
            r = http.post("/api/predict?horizon_s=5", json={"pattern": "circle", "params": CIRCLE})
            assert r.status_code == 200, r.text
        workers = _children(console.pid) - before
        assert workers, "the prediction ran in no worker process"
        # background work: the twin's worker (not multiprocessing's resource tracker) yields
        # the CPU to the console's requests
        twins = {p for p in workers if b"spawn_main" in Path(f"/proc/{p}/cmdline").read_bytes()}
        assert twins, "no spawned worker among the console's children"
        assert {_nice(p) for p in twins} == {min(19, _nice(console.pid) + WORKER_NICE)}
    finally:
        console.stop() if ending == "stop" else console.kill()
    wait_until(lambda: not any(_alive(p) for p in workers), what="the worker to exit")
