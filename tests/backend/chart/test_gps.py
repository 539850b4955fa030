"""The surface GPS: the setting's forms, NMEA sentences over a loopback UDP socket and a
pseudo-terminal (the serial path), bad sentences counted and never raised, the latest fix
wins, the station follows it, and a console without a datum takes the first fix as its
datum."""

from __future__ import annotations

import asyncio
import functools
import os
import random
import socket
import time
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError

from backend.chart.geo import TRAINING_DATUM, Datum, geodetic_to_ned
from backend.chart.gps import GpsReader, GpsSource, parse_gps, station_of
from backend.settings import Settings
from tests.backend.conftest import AUTH, MakeClient, clear_nemesys_env, console_of, wait_until


def nmea(body: str) -> str:
    """A sentence with its checksum (XOR of the characters between $ and *)."""
    checksum = functools.reduce(lambda a, c: a ^ ord(c), body, 0)
    return f"${body}*{checksum:02X}"


#: Real sentences (NMEA 0183's reference examples, their checksums as published).
GGA_MUNICH = "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47"
RMC_MUNICH = "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A"
#: The same GGA with its checksum wrong.
GGA_BAD_CHECKSUM = GGA_MUNICH[:-2] + "48"
#: The training site, 29°31.896'N 082°18.186'W, a DGPS fix; and 300 m north-east of it.
GGA_SITE = nmea("GNGGA,101500.00,2931.896,N,08218.186,W,2,12,0.8,1.2,M,-30.1,M,,")
RMC_NEAR = nmea("GPRMC,101501.00,A,2932.011,N,08218.055,W,0.1,0.0,241126,,,A")
GGA_NO_FIX = nmea("GPGGA,101502.00,,,,,0,00,99.99,,,,,,")
RMC_VOID = nmea("GPRMC,101503.00,V,,,,,,,241126,,,N")
GSV = nmea("GPGSV,1,1,01,05,45,120,40")


async def until(probe: Callable[[], Any], timeout_s: float = 10.0) -> Any:
    """Poll ``probe`` on the loop until truthy (a deadline, never a fixed sleep)."""
    deadline = time.monotonic() + timeout_s
    while not (value := probe()):
        assert time.monotonic() < deadline, f"timed out waiting for {probe}"
        await asyncio.sleep(0.01)
    return value


def run(coro: Callable[[], Awaitable[None]]) -> None:
    asyncio.run(coro())  # type: ignore[arg-type]


# --- the setting -----------------------------------------------------------------------------


def test_the_setting_forms() -> None:
    assert parse_gps("") is None
    assert parse_gps("  ") is None
    assert parse_gps("udp://127.0.0.1:10110") == GpsSource("udp", host="127.0.0.1", port=10110)
    assert parse_gps("serial:///dev/ttyUSB1?baud=9600") == GpsSource(
        "serial", device="/dev/ttyUSB1", baud=9600
    )
    assert parse_gps("serial:///dev/ttyUSB1").baud == 4800  # type: ignore[union-attr]
    assert str(parse_gps("udp://127.0.0.1:10110")) == "udp://127.0.0.1:10110"


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ("/dev/ttyUSB1", "no scheme"),
        ("tcp://127.0.0.1:10110", "unknown scheme 'tcp'"),
        ("udp://127.0.0.1", "no port"),
        ("udp://127.0.0.1:99999", "port must be a number"),
        ("udp://:10110", "no host"),
        ("udp://127.0.0.1:10110/x", "only host:port"),
        ("serial://dev/ttyUSB1", "must be absolute"),
        ("serial:///dev/ttyUSB1?baud=fast", "baud must be a positive whole number"),
        ("serial:///dev/ttyUSB1?parity=N", "unknown option 'parity'"),
    ],
)
def test_a_bad_setting_names_the_problem_and_the_allowed_forms(value: str, problem: str) -> None:
    with pytest.raises(ValueError, match="allowed") as caught:
        parse_gps(value)
    text = str(caught.value)
    assert problem in text
    assert "udp://127.0.0.1:10110" in text and "serial:///dev/" in text


def test_settings_validate_gps_like_target(monkeypatch: pytest.MonkeyPatch) -> None:
    clear_nemesys_env(monkeypatch)
    with pytest.raises(ValidationError) as caught:
        Settings(token="t" * 20, gps="gps0")
    error = caught.value.errors()[0]
    assert error["loc"] == ("gps",)
    assert "udp://" in error["msg"] and "serial://" in error["msg"]
    assert Settings(token="t" * 20, gps="udp://127.0.0.1:10110").gps == "udp://127.0.0.1:10110"


# --- the reader ------------------------------------------------------------------------------


def test_sentences_over_loopback_udp_are_counted_and_the_latest_fix_wins() -> None:
    seen: list[Any] = []

    async def main() -> None:
        reader = GpsReader(GpsSource("udp", host="127.0.0.1", port=0), on_fix=seen.append)
        await reader.start()
        assert reader.port
        sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:

            def send(*lines: str) -> None:
                sender.sendto("\r\n".join(lines).encode() + b"\r\n", ("127.0.0.1", reader.port))

            send(GGA_MUNICH)
            fix = await until(lambda: reader.fix)
            assert (fix.lat_deg, fix.lon_deg) == pytest.approx((48.1173, 11.5166667), abs=1e-6)
            assert fix.quality == 1 and fix.sentence == "GGA"
            assert fix.age_s() >= 0
            # several sentences in one datagram; a bad checksum, garbage, no-fix and other
            # sentence types are counted, never raised, and leave the fix alone
            send(GGA_BAD_CHECKSUM, "hello, world", GGA_NO_FIX, RMC_VOID, GSV)
            await until(lambda: reader.sentences == 6)
            assert reader.errors == 2 and reader.no_fix == 2 and reader.fixes == 1
            assert reader.last_error is not None and "hello, world" in reader.last_error
            assert reader.fix is fix
            send(GGA_BAD_CHECKSUM)
            await until(lambda: reader.errors == 3)
            assert reader.last_error is not None and "checksum" in reader.last_error
            # the latest fix wins, whatever the sentence type
            send(GGA_SITE, RMC_NEAR)
            await until(lambda: reader.fixes == 3)
            last = reader.fix
            assert last is not None and last.sentence == "RMC" and last.quality is None
            assert (last.lat_deg, last.lon_deg) == pytest.approx(
                (29.53351667, -82.30091667), abs=1e-7
            )
            assert [f.sentence for f in seen] == ["GGA", "GGA", "RMC"]
            assert seen[1].quality == 2
            doc = reader.doc()
            assert doc["fix"] is True and doc["sentences"] == 9 and doc["errors"] == 3
            assert doc["source"] == f"udp://127.0.0.1:{reader.port}"
        finally:
            sender.close()
            await reader.stop()

    run(main)


def test_a_sentence_split_across_datagrams_and_a_failing_consumer() -> None:
    """Text arrives in pieces (serial reads, split datagrams): only whole lines are parsed;
    an ``on_fix`` that raises does not stop the reader."""

    def boom(_fix: object) -> None:
        raise RuntimeError("consumer bug")

    reader = GpsReader(GpsSource("udp", host="127.0.0.1", port=0), on_fix=boom)
    reader.feed(GGA_MUNICH[:30])
    assert reader.sentences == 0
    reader.feed(GGA_MUNICH[30:] + "\r\n" + GGA_SITE[:10])
    assert reader.sentences == 1 and reader.fix is not None and reader.errors == 0
    reader.feed(GGA_SITE[10:] + "\n")
    assert reader.fixes == 2
    assert reader.fix.lat_deg == pytest.approx(29.5316, abs=1e-6)
    reader.feed_line(nmea("GPGGA,1,99xx.1,N,00000.0,E,1,5,1,0,M,0,M,,"))  # not a number
    reader.feed_line("$GPGGA,1,2931.896,N,08218.186,W,1,5,1,0,M,0,M,,")  # no checksum
    reader.feed_line(nmea("GPGGA,1,9130.000,N,00000.000,E,1,5,1,0,M,0,M,,"))  # 91.5 deg N
    assert reader.errors == 3 and reader.fixes == 2
    assert reader.last_error is not None and "lat_deg" in reader.last_error


def test_no_line_makes_the_reader_raise() -> None:
    """Random and mangled lines (a noisy serial line, a fuzzer on the UDP port): each is
    counted as a sentence and, but for a valid one, an error or no-fix; none raises."""
    rng = random.Random(14)
    reader = GpsReader(GpsSource("udp", host="127.0.0.1", port=0))
    # a sentence cut short (no checksum) is never a position: 29°31.8' is not 29°31.896'
    cut = [GGA_SITE[: rng.randrange(len(GGA_SITE) - 3)] for _ in range(200)]
    for line in cut:
        reader.feed_line(line)
    assert reader.errors == 200 and reader.fix is None
    assert reader.last_error is not None and "checksum" in reader.last_error
    alphabet = "$*,.0123456789ABCDEFGNPRSWVX\x00\xff\u00e9 "
    noise = ["".join(rng.choice(alphabet) for _ in range(rng.randrange(1, 90))) for _ in range(500)]
    noise += [nmea("GPGGA," + ",".join(rng.choice(["", "x", "1", "-", "N"]) for _ in range(14)))]
    noise += [nmea("GPRMC," + ",".join(rng.choice(["", "A", "1e9", "N"]) for _ in range(11)))]
    for line in noise:
        reader.feed_line(line)
    assert reader.sentences == len(cut) + len(noise)
    assert reader.errors >= 700


@pytest.mark.slow  # a pseudo-terminal read at its real pace
def test_the_serial_path_reads_a_pseudo_terminal() -> None:
    """serial:///dev/pts/N: the pyserial thread reads what the other end writes."""
    master, slave = os.openpty()
    source = GpsSource("serial", device=os.ttyname(slave), baud=4800)

    async def main() -> None:
        reader = GpsReader(source)
        await reader.start()
        try:
            await until(lambda: reader.open)  # pyserial flushes its input when it opens
            os.write(master, (GGA_SITE + "\r\n").encode())
            fix = await until(lambda: reader.fix)
            assert fix.lat_deg == pytest.approx(TRAINING_DATUM.lat_deg, abs=1e-6)
            assert fix.lon_deg == pytest.approx(TRAINING_DATUM.lon_deg, abs=1e-6)
            os.write(master, (GGA_BAD_CHECKSUM + "\r\n").encode())
            await until(lambda: reader.errors == 1)
        finally:
            await reader.stop()

    try:
        run(main)
    finally:
        os.close(master)
        os.close(slave)


def test_a_missing_serial_device_is_an_error_kept_not_raised() -> None:
    async def main() -> None:
        reader = GpsReader(GpsSource("serial", device="/dev/nemesys-no-such-gps"))
        await reader.start()
        try:
            await until(lambda: reader.last_error)
            assert "/dev/nemesys-no-such-gps" in str(reader.last_error)
        finally:
            await reader.stop()

    run(main)


# --- the station -----------------------------------------------------------------------------


def test_the_station_is_the_fix_else_the_settings_else_the_datum() -> None:
    datum = TRAINING_DATUM
    reader = GpsReader(GpsSource("udp", host="127.0.0.1", port=0))
    assert station_of(datum, None).as_dict() == {
        "lat_deg": datum.lat_deg,
        "lon_deg": datum.lon_deg,
        "x_m": 0.0,
        "y_m": 0.0,
        "source": "datum",
        "age_s": None,
    }
    assert station_of(None, None).source == "datum"
    assert station_of(None, None).lat_deg is None
    placed = station_of(datum, None, 29.532, -82.303)
    assert placed.source == "settings" and placed.age_s is None
    assert (placed.x_m, placed.y_m) == pytest.approx(geodetic_to_ned(datum, 29.532, -82.303))
    assert placed.x_m == pytest.approx(44.3, abs=0.1)  # 0.0004 deg of latitude
    # without a datum the settings' station has a lat/lon but no place in NED
    unplaced = station_of(None, None, 29.532, -82.303)
    assert unplaced.x_m is None and unplaced.lat_deg == 29.532
    reader.feed_line(RMC_NEAR)
    gps = station_of(datum, reader.fix, 29.532, -82.303)
    assert gps.source == "gps" and gps.age_s is not None and gps.age_s >= 0
    x, y = geodetic_to_ned(datum, 29.53351667, -82.30091667)
    assert (gps.x_m, gps.y_m) == pytest.approx((x, y), abs=0.01)
    # 0.115' of latitude, 0.131' of longitude at 29.5 N: about 212 m each way
    assert 205 < (gps.x_m or 0) < 220 and 205 < (gps.y_m or 0) < 220


# --- a console -------------------------------------------------------------------------------


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def send_udp(port: int, *lines: str) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.sendto("\r\n".join(lines).encode() + b"\r\n", ("127.0.0.1", port))


def test_a_vehicle_console_without_a_datum_takes_the_first_fix(make_client: MakeClient) -> None:
    port = free_udp_port()
    client: TestClient = make_client(target="loop://", gps=f"udp://127.0.0.1:{port}")
    assert client.get("/api/session").json()["datum"] is None
    chart = client.get("/api/chart").json()
    assert chart["datum"] is None
    assert chart["station"] == {
        "lat_deg": None,
        "lon_deg": None,
        "x_m": 0.0,
        "y_m": 0.0,
        "source": "datum",
        "age_s": None,
    }
    assert chart["gps"]["configured"] is True and chart["gps"]["fix"] is False
    # no fix yet: the datum cannot come from it
    r = client.put("/api/datum", json={"source": "gps"}, headers=AUTH)
    assert r.status_code == 409 and "no fix yet" in r.json()["detail"]
    send_udp(port, GGA_BAD_CHECKSUM, GGA_SITE)
    session = wait_until(lambda: client.get("/api/session").json()["datum"], what="a datum")
    assert session == pytest.approx({"lat_deg": 29.5316, "lon_deg": -82.3031}, abs=1e-9)
    # a later fix moves the station, not the datum
    send_udp(port, RMC_NEAR)
    chart = wait_until(
        lambda: (c := client.get("/api/chart").json())["gps"]["sentences"] == 3 and c,
        what="the second fix",
    )
    assert chart["datum"] == session
    assert chart["gps"]["errors"] == 1 and "checksum" in chart["gps"]["last_error"]
    station = chart["station"]
    assert station["source"] == "gps" and station["age_s"] >= 0
    x, y = geodetic_to_ned(Datum(29.5316, -82.3031), 29.53351667, -82.30091667)
    assert (station["x_m"], station["y_m"]) == pytest.approx((x, y), abs=0.01)
    # the operator may move the datum to the latest fix
    r = client.put("/api/datum", json={"source": "gps"}, headers=AUTH)
    assert r.status_code == 200, r.text
    moved = r.json()
    assert moved["datum"] == pytest.approx({"lat_deg": 29.53351667, "lon_deg": -82.30091667})
    assert (moved["station"]["x_m"], moved["station"]["y_m"]) == pytest.approx((0, 0), abs=1e-6)
    assert console_of(client).datum == Datum(moved["datum"]["lat_deg"], moved["datum"]["lon_deg"])


def test_a_configured_datum_is_kept_when_the_gps_gets_a_fix(make_client: MakeClient) -> None:
    port = free_udp_port()
    client = make_client(
        target="loop://", gps=f"udp://127.0.0.1:{port}", datum_lat_deg=29.5, datum_lon_deg=-82.3
    )
    send_udp(port, RMC_NEAR)
    chart = wait_until(
        lambda: (c := client.get("/api/chart").json())["gps"]["fix"] and c, what="a fix"
    )
    assert chart["datum"] == {"lat_deg": 29.5, "lon_deg": -82.3}
    assert chart["station"]["source"] == "gps"
    # 2.011' north of 29.5 N, where a minute of latitude is 1847.5 m
    assert chart["station"]["x_m"] == pytest.approx(2.011 * 1847.5, abs=2)
