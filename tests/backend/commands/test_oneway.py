"""One-way delivery on the wire: the console against a TCP "modem gateway" that decodes every
frame it receives. Copies spaced in time, the one supersede rule (no frame of an older command
after the first frame of a newer one), a bounded Surface, joined Surface presses, the operator's
copies, shutdown, and the link health the station reports for a one-way link."""

from __future__ import annotations

import contextlib
import itertools
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError

from backend.app import create_app
from backend.mission_log.store import MissionLog
from backend.settings import Settings
from bench._gateway import FrameGateway
from codec import delivery_probability
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    FINAL,
    MakeClient,
    clear_nemesys_env,
    console_of,
    record,
    settings_for,
    wait_state,
    wait_until,
)

HOVER: dict[str, Any] = {"duration": 60, "depth": 3, "heading": 90}


@pytest.fixture
def wire() -> Iterator[FrameGateway]:
    w = FrameGateway()
    try:
        yield w
    finally:
        w.close()
        assert not w.rejected, f"frames the gateway could not decode: {w.rejected}"


def show_trace(
    wire: FrameGateway, records: dict[int, dict[str, Any]], title: str, out: Path | None = None
) -> str:
    """The wire trace, times relative to the first frame, each frame named by its record;
    printed (visible with ``pytest -s``) and written best-effort to ``out``."""
    by_hex: dict[str, list[int]] = {}
    for cid, rec in records.items():
        by_hex.setdefault(rec["hex"], []).append(cid)
    trace = wire.trace()
    t0 = trace[0].t if trace else 0.0
    lines = [f"wire trace: {title} ({len(trace)} frames)"]
    for i, f in enumerate(trace):
        ids = ",".join(str(c) for c in by_hex.get(f.hex, [])) or "?"
        params = " ".join(
            f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in f.params.items()
        )
        lines.append(
            f"  {i:2d}  +{f.t - t0:7.3f} s  command {ids:>3}  {f.pattern:<8} {params:<40} {f.hex}"
        )
    text = "\n".join(lines)
    print("\n" + text)
    if out is not None:
        with contextlib.suppress(OSError):
            out.write_text(text + "\n")
    return text


def indices(wire: FrameGateway, hex_: str) -> list[int]:
    """Positions in the wire trace of the frames with these bits."""
    return [i for i, f in enumerate(wire.trace()) if f.hex == hex_]


def post_surface(client: TestClient) -> dict[str, Any]:
    r = client.post("/api/surface", headers=AUTH)
    assert r.status_code == 202, r.text
    body: dict[str, Any] = r.json()
    return body


def post_command(
    client: TestClient, pattern: str, params: dict[str, Any], copies: int | None = None
) -> dict[str, Any]:
    body: dict[str, Any] = {"pattern": pattern, "params": params}
    if copies is not None:
        body["copies"] = copies
    r = client.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    out: dict[str, Any] = r.json()
    return out


def wait_for_frames(wire: FrameGateway, hex_: str, n: int) -> None:
    wait_until(lambda: wire.count(hex_) >= n, what=f"{n} frames {hex_} on the wire")


def post_copies(client: TestClient, copies: object) -> Any:
    """POST a circle with this ``copies`` (any JSON value); the response."""
    body = {"pattern": "circle", "params": CIRCLE, "copies": copies}
    return client.post("/api/commands", json=body, headers=AUTH)


def assert_silent(client: TestClient, wire: FrameGateway) -> None:
    """No frame will reach the wire any more (conditions, not a wait for absence): every
    frame leaves from a live delivery under the transmit lock, so with none live and the lock
    free nothing more leaves until the next request; and every copy the log counts is on the
    wire, so none is still in flight."""
    cm = console_of(client).commands
    assert cm is not None
    wait_until(lambda: not cm._live and not cm._tx_lock.locked(), what="every delivery to end")
    counted = sum(r["copies_sent"] for r in client.get("/api/commands").json())
    wait_until(lambda: len(wire.trace()) >= counted, what=f"the {counted} copies on the wire")
    assert len(wire.trace()) == counted, f"frames the log does not count: {wire.trace()}"


# --- a. Surface then hover ------------------------------------------------------------------


@pytest.mark.parametrize("before", [1, 2])
def test_surface_then_hover_no_surface_frame_after_the_hover(
    make_client: MakeClient, wire: FrameGateway, tmp_path: Path, before: int
) -> None:
    """The hover is sent after ``before`` surface frames are on the wire."""
    repeat_s = 0.3
    client = make_client(target=wire.target, surface_repeat_s=repeat_s, copy_interval_s=0.1)
    surface = post_surface(client)
    assert surface["kind"] == "surface" and surface["copies"] == 3
    wait_until(lambda: wire.count(surface["hex"]) >= before, what=f"{before} surface frames")
    hover = post_command(client, "hover", HOVER)
    assert hover["copies"] == 1 and hover["two_way"] is False  # link_ber 1e-3 -> 1 copy
    h = wait_state(client, hover["id"])
    s = record(client, surface["id"])
    assert_silent(client, wire)  # nothing more, in particular no late surface repeat
    text = show_trace(
        wire,
        {surface["id"]: s, hover["id"]: h},
        f"Surface, then a hover after {before} surface frame(s)",
        tmp_path / f"wire-trace-surface-hover-{before}.txt",
    )

    first_hover = indices(wire, hover["hex"])[0]
    late = [i for i in indices(wire, surface["hex"]) if i > first_hover]
    assert not late, f"surface frames after the hover's first frame:\n{text}"
    assert s["state"] == "superseded" and s["superseded_by"] == hover["id"], s
    assert s["copies_sent"] == wire.count(surface["hex"]) >= before
    assert h["state"] == "sent", h
    assert h["copies_sent"] == h["copies"] == wire.count(hover["hex"]) == 1
    assert wire.trace()[first_hover].pattern == "hover"
    assert wire.trace()[first_hover].params == {"duration": 60.0, "depth": 3.0, "heading": 90.0}


# --- b. Surface alone -------------------------------------------------------------------


def test_surface_alone_stops_after_its_bounded_repeats(
    make_client: MakeClient, wire: FrameGateway
) -> None:
    repeat_s = 0.15
    client = make_client(target=wire.target, surface_repeat_s=repeat_s, link_ber=1e-3)
    surface = post_surface(client)
    rec = wait_state(client, surface["id"])
    assert rec["state"] == "sent", rec
    assert rec["copies"] == rec["copies_sent"] == 3  # at 1e-3: MIN_SURFACE_COPIES
    assert rec["attempts"] == 3 and rec["two_way"] is False
    assert_silent(client, wire)
    trace = wire.trace()
    assert [f.pattern for f in trace] == ["surface"] * 3
    assert wire.count(surface["hex"]) == 3
    gaps = [b.t - a.t for a, b in itertools.pairwise(trace)]
    assert all(g >= 0.8 * repeat_s for g in gaps), gaps  # spaced, not a burst
    assert record(client, surface["id"])["state"] == "sent"  # still: nothing reopened it


def test_a_surface_frame_sent_as_a_command_is_delivered_as_a_surface(
    make_client: MakeClient, wire: FrameGateway
) -> None:
    """Whichever way a surface frame is sent, it gets a Surface's copies, and the button
    pressed meanwhile joins it."""
    client = make_client(target=wire.target, surface_repeat_s=0.15, link_ber=1e-3)
    rec = post_command(client, "surface", {})
    assert rec["kind"] == "surface" and rec["origin"] == "api"
    assert rec["copies"] == 3  # not the 1 copy of a command
    wait_for_frames(wire, rec["hex"], 1)
    assert post_surface(client)["id"] == rec["id"]  # joined, not a second record
    done = wait_state(client, rec["id"])
    assert done["state"] == "sent" and done["copies_sent"] == done["copies"] >= 4
    assert wire.count(rec["hex"]) == done["copies_sent"]


# --- c. three circles, Surface, hover ---------------------------------------------------


def test_three_circles_surface_hover_in_order(
    make_client: MakeClient, wire: FrameGateway, tmp_path: Path
) -> None:
    """The issue's scenario ("on the wire: three circles, then Surface, then a hover, then
    more surface frames after the hover"): each command is replaced after two of its copies;
    no frame of an older record follows the first frame of a newer one."""
    repeat_s = 0.25
    client = make_client(target=wire.target, surface_repeat_s=repeat_s, copy_interval_s=0.25)
    sent: list[dict[str, Any]] = []
    for radius in (5, 6, 7):
        cmd = post_command(client, "circle", {**CIRCLE, "radius": radius}, copies=5)
        sent.append(cmd)
        wait_for_frames(wire, cmd["hex"], 2)
    surface = post_surface(client)
    sent.append(surface)
    wait_until(lambda: wire.count(surface["hex"]) >= 2, what="two surface frames")
    hover = post_command(client, "hover", HOVER)
    sent.append(hover)
    wait_state(client, hover["id"])
    assert_silent(client, wire)
    records = {c["id"]: record(client, c["id"]) for c in sent}
    text = show_trace(
        wire,
        records,
        "three circles, Surface, hover",
        tmp_path / "wire-trace-circles-surface-hover.txt",
    )

    assert len({c["hex"] for c in sent}) == len(sent)  # each record is told apart by its bits
    for rec in records.values():
        assert rec["state"] in FINAL, rec
    for older, newer in itertools.pairwise(sent):
        old_frames, new_frames = indices(wire, older["hex"]), indices(wire, newer["hex"])
        assert old_frames and new_frames, text
        late = [i for i in old_frames if i > new_frames[0]]
        assert not late, (
            f"frames of command {older['id']} after the first of {newer['id']}: {late}\n{text}"
        )
        rec = records[older["id"]]
        assert rec["state"] == "superseded" and rec["superseded_by"] == newer["id"], rec
        assert rec["copies_sent"] == len(old_frames)
    h = records[hover["id"]]
    assert h["state"] == "sent" and h["copies_sent"] == h["copies"] == 1
    assert len(wire.trace()) == sum(r["copies_sent"] for r in records.values())


# --- d. concurrent Surface presses ------------------------------------------------------


def test_twenty_concurrent_surface_presses_are_one_record(
    make_client: MakeClient, wire: FrameGateway
) -> None:
    client = make_client(target=wire.target, surface_repeat_s=0.3)
    barrier = threading.Barrier(20)

    def press(_: int) -> tuple[int, dict[str, Any]]:
        barrier.wait(5)
        r = client.post("/api/surface", headers=AUTH)
        return r.status_code, r.json()

    with ThreadPoolExecutor(20) as pool:
        replies = list(pool.map(press, range(20)))
    assert [code for code, _ in replies] == [202] * 20, replies
    ids = {body["id"] for _, body in replies}
    assert len(ids) == 1, f"one Surface record, got {sorted(ids)}"
    (sid,) = ids
    rows = client.get("/api/commands").json()
    assert [r["id"] for r in rows] == [sid]
    assert not [r for r in rows if r["state"] == "queued" and r["attempts"] == 0], rows
    rec = wait_state(client, sid, timeout_s=15.0)
    assert rec["state"] == "sent", rec
    assert rec["copies_sent"] == rec["copies"] >= 3
    assert rec["attempts"] == rec["copies_sent"]
    assert_silent(client, wire)
    assert wire.count(rec["hex"]) == rec["copies_sent"] == len(wire.trace())


# --- e. the operator's copies -----------------------------------------------------------


def test_copies_override_goes_out_that_many_times(
    make_client: MakeClient, wire: FrameGateway
) -> None:
    ber = 1e-2
    client = make_client(target=wire.target, copy_interval_s=0.05, link_ber=ber)
    assert client.get("/api/vehicle").json()["link"]["copies"] == 3  # chosen at 1e-2
    cmd = post_command(client, "circle", CIRCLE, copies=4)
    assert cmd["copies"] == 4
    rec = wait_state(client, cmd["id"])
    assert rec["state"] == "sent", rec
    assert rec["copies"] == rec["copies_sent"] == 4
    assert rec["p_delivered"] == pytest.approx(delivery_probability(ber, 4), rel=1e-12)
    assert rec["ber"] == ber
    assert_silent(client, wire)
    assert wire.count(cmd["hex"]) == 4 == len(wire.trace())


@pytest.mark.parametrize(("copies", "bound"), [(0, "1"), (21, "20")])
def test_copies_out_of_range_are_422_naming_copies(
    make_client: MakeClient, copies: int, bound: str
) -> None:
    client = make_client(target="loop://")
    r = post_copies(client, copies)
    assert r.status_code == 422, r.text
    (error,) = r.json()["detail"]
    assert "copies" in error["loc"], error
    assert bound in error["msg"], error
    assert client.get("/api/commands").json() == []


@pytest.mark.parametrize("copies", ["3", True, 2.5])
def test_copies_of_the_wrong_type_are_422_naming_copies_and_the_range(
    make_client: MakeClient, copies: object
) -> None:
    client = make_client(target="loop://")
    r = post_copies(client, copies)
    assert r.status_code == 422, r.text
    assert client.get("/api/commands").json() == []
    (error,) = r.json()["detail"]
    assert "copies" in error["loc"], error
    assert "1" in error["msg"] and "20" in error["msg"], error


@pytest.mark.parametrize(
    ("field", "value"),
    [("link_ber", 0.5), ("link_ber", -0.1), ("delivery_target", 0), ("delivery_target", 1)],
)
def test_link_settings_out_of_range_are_refused_not_clamped(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, field: str, value: float
) -> None:
    clear_nemesys_env(monkeypatch)
    with pytest.raises(ValidationError) as err:
        values: dict[str, Any] = {
            "token": "x" * 20,
            "db_path": tmp_path / "m.sqlite3",
            field: value,
        }
        Settings(**values)
    assert [e["loc"] for e in err.value.errors()] == [(field,)]
    assert field in str(err.value)


# --- f. shutdown during repeats ---------------------------------------------------------


@pytest.mark.slow  # real copies 0.5 s apart on a TCP modem, ~2 s
def test_shutdown_during_repeats_interrupts_and_silences(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, wire: FrameGateway
) -> None:
    clear_nemesys_env(monkeypatch)
    db = tmp_path / "shutdown.sqlite3"
    interval_s = 0.5
    settings = settings_for(db, target=wire.target, copy_interval_s=interval_s)
    with TestClient(create_app(settings, viewer=False)) as client:
        cmd = post_command(client, "circle", CIRCLE, copies=20)
        wait_until(lambda: wire.count(cmd["hex"]) >= 2, what="two copies on the wire")
    stopped = time.monotonic()
    log = MissionLog(db)
    try:
        rec = log.command(cmd["id"])
    finally:
        log.close()
    assert rec is not None
    assert rec["state"] == "interrupted", rec
    assert "shut down" in (rec["reason"] or ""), rec
    assert 2 <= rec["copies_sent"] < 20
    # stopped: every delivery task was awaited and the link closed; what left is counted
    wait_until(lambda: wire.count(cmd["hex"]) >= rec["copies_sent"], what="the copies sent")
    late = [f for f in wire.trace() if f.t > stopped]
    assert not late, f"frames after shutdown: {late}"
    assert wire.count(cmd["hex"]) == rec["copies_sent"] == rec["attempts"]


# --- g. link health of a one-way link ---------------------------------------------------


def test_vehicle_link_of_a_tcp_modem(make_client: MakeClient, wire: FrameGateway) -> None:
    client = make_client(target=wire.target, copy_interval_s=0.05, surface_repeat_s=0.05)
    link = client.get("/api/vehicle").json()["link"]
    assert link["target"] == wire.target
    assert (link["capability"], link["level"], link["connected"]) == ("none", "amber", True)
    assert link["acknowledges"] is False and link["telemetry"] is False
    assert any("one-way" in p for p in link["problems"]), link["problems"]
    assert link["frames"]["dive"]["frames"] == 0
    assert (link["copies"], link["surface_copies"], link["ber"]) == (1, 3, 1e-3)
    assert client.get("/api/session").json()["link"] == {
        "capability": "none",
        "acknowledges": False,
        "telemetry": False,
    }

    cmd = post_command(client, "circle", CIRCLE, copies=2)
    wait_state(client, cmd["id"])
    surface = post_surface(client)
    wait_state(client, surface["id"])
    on_wire = len(wire.trace())
    assert on_wire == 5  # 2 copies + 3 surface
    v = client.get("/api/vehicle")
    assert v.status_code == 200
    link = v.json()["link"]
    assert link["capability"] == "none" and link["level"] == "amber"
    dive = link["frames"]["dive"]
    assert dive == {
        "frames": on_wire,
        "sent": on_wire,
        "acknowledged": 0,
        "rejected": 0,
        "timed_out": 0,
    }
    assert link["frames"]["recent"]["frames"] == on_wire
    assert link["frames"]["recent"]["sent"] == on_wire
    assert link["last_ack_age_s"] is None and link["last_telemetry_age_s"] is None
    assert wire.connections == 1
