"""Local map tiles: a directory of z/x/y tiles and an MBTiles file (TMS rows flipped to the
XYZ rows Leaflet asks for), their media types and zoom range, 404 for a missing tile or no
tiles, 422 naming the index out of range, nothing served from outside the directory."""

from __future__ import annotations

import sqlite3
import struct
import zlib
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from backend.chart.tiles import MbTiles, open_tiles, sniff
from tests.backend.conftest import MakeClient, console_of, loc_of


def png(seed: int) -> bytes:
    """A valid 1x1 PNG whose grey level is ``seed`` (distinct tiles, distinct bytes)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0)
    pixels = zlib.compress(bytes([0, seed % 256]))
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", pixels) + chunk(b"IEND", b"")
    )


JPEG = b"\xff\xd8\xff\xe0\x00\x10JFIF\x00" + b"\x00" * 16 + b"\xff\xd9"
WEBP = (
    b"RIFF\x1a\x00\x00\x00WEBPVP8L\x0d\x00\x00\x00"
    b"\x2f\x00\x00\x00\x10\x07\x10\x11\x11\x88\x88\xfe\x07\x00"
)


def tile_dir(root: Path) -> Path:
    tiles = root / "tiles"
    for (z, x, y), data, ext in (
        ((3, 2, 5), png(1), "png"),
        ((3, 7, 0), png(2), "png"),
        ((4, 1, 15), JPEG, "jpg"),
        ((5, 31, 31), WEBP, "webp"),
    ):
        path = tiles / str(z) / str(x) / f"{y}.{ext}"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    (tiles / "notes").mkdir()  # not a zoom level
    (tiles / "README.txt").write_text("tiles from a survey")
    return tiles


def mbtiles(path: Path, *, fmt: str = "png", zoom_meta: bool = True) -> Path:
    db = sqlite3.connect(path)
    db.executescript(
        "CREATE TABLE metadata (name TEXT, value TEXT);"
        "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, "
        "tile_data BLOB);"
    )
    meta = [("name", "survey"), ("format", fmt)]
    if zoom_meta:
        meta += [("minzoom", "1"), ("maxzoom", "2")]
    db.executemany("INSERT INTO metadata VALUES (?, ?)", meta)
    # zoom 2 has rows 0..3; TMS row 0 is the southernmost, XYZ row 3
    db.executemany(
        "INSERT INTO tiles VALUES (?, ?, ?, ?)",
        [(2, 1, 0, png(10)), (2, 1, 3, png(13)), (1, 0, 1, png(21)), (2, 2, 2, JPEG)],
    )
    db.commit()
    db.close()
    return path


def test_sniff() -> None:
    assert sniff(png(0)) == "png"
    assert sniff(JPEG) == "jpg"
    assert sniff(WEBP) == "webp"
    assert sniff(b"GIF89a") is None


def test_a_directory_of_tiles(make_client: MakeClient, tmp_path: Path) -> None:
    client = make_client(tiles=tile_dir(tmp_path))
    tiles = client.get("/api/chart").json()["tiles"]
    assert tiles == {
        "url": "/api/tiles/{z}/{x}/{y}",
        "kind": "directory",
        "min_zoom": 3,
        "max_zoom": 5,
        "format": "png",
    }
    for url, body, media in (
        ("/api/tiles/3/2/5", png(1), "image/png"),
        ("/api/tiles/3/7/0", png(2), "image/png"),
        ("/api/tiles/4/1/15", JPEG, "image/jpeg"),
        ("/api/tiles/5/31/31", WEBP, "image/webp"),
    ):
        r = client.get(url)
        assert r.status_code == 200, (url, r.text)
        assert r.content == body and r.headers["content-type"] == media
    for url in ("/api/tiles/3/5/2", "/api/tiles/0/0/0", "/api/tiles/30/1/1"):
        r = client.get(url)
        assert r.status_code == 404 and "no tile" in r.json()["detail"]


def test_out_of_range_indices_are_422_naming_the_field(client: TestClient) -> None:
    for url, field, words in (
        ("/api/tiles/3/8/0", "x", "x must be in [0, 7] at zoom 3"),
        ("/api/tiles/3/0/8", "y", "y must be in [0, 7] at zoom 3"),
        ("/api/tiles/0/1/0", "x", "x must be in [0, 0] at zoom 0"),
        ("/api/tiles/31/0/0", "z", "less than or equal to 30"),
        ("/api/tiles/-1/0/0", "z", "greater than or equal to 0"),
        ("/api/tiles/2/-1/0", "x", "greater than or equal to 0"),
        ("/api/tiles/2/0/y", "y", "valid integer"),
        ("/api/tiles/2/0/1.png", "y", "valid integer"),
    ):
        r = client.get(url)
        assert r.status_code == 422, (url, r.text)
        assert loc_of(r.json()) == ["path", field], url
        assert words in r.json()["detail"][0]["msg"], (url, r.text)


def test_no_tiles_configured(client: TestClient) -> None:
    assert client.get("/api/chart").json()["tiles"] is None
    r = client.get("/api/tiles/3/2/5")
    assert r.status_code == 404 and "no local map tiles" in r.json()["detail"]


def test_nothing_outside_the_directory_is_served(make_client: MakeClient, tmp_path: Path) -> None:
    """The indices are integers, so no request names a path; a link inside the directory
    that leads out of it is not followed either."""
    root = tile_dir(tmp_path)
    secret = tmp_path / "secret.png"
    secret.write_bytes(png(99))
    (root / "3" / "1").mkdir()
    (root / "3" / "1" / "1.png").symlink_to(secret)
    client = make_client(tiles=root)
    assert client.get("/api/tiles/3/1/1").status_code == 404
    for url in ("/api/tiles/3/2/..%2F..%2Fsecret", "/api/tiles/3/%2E%2E/5", "/api/tiles/../3/2/5"):
        assert client.get(url).status_code in (404, 422), url
    assert client.get("/api/tiles/3/2/5").status_code == 200


def test_an_mbtiles_file_flips_tms_rows(make_client: MakeClient, tmp_path: Path) -> None:
    path = mbtiles(tmp_path / "survey.mbtiles")
    client = make_client(tiles=path)
    assert client.get("/api/chart").json()["tiles"] == {
        "url": "/api/tiles/{z}/{x}/{y}",
        "kind": "mbtiles",
        "min_zoom": 1,
        "max_zoom": 2,
        "format": "png",
    }
    # XYZ y = 2^z - 1 - TMS row
    assert client.get("/api/tiles/2/1/3").content == png(10)  # TMS row 0
    assert client.get("/api/tiles/2/1/0").content == png(13)  # TMS row 3
    assert client.get("/api/tiles/1/0/0").content == png(21)  # TMS row 1 at zoom 1
    jpeg = client.get("/api/tiles/2/2/1")  # TMS row 2; sniffed, whatever the metadata says
    assert jpeg.headers["content-type"] == "image/jpeg" and jpeg.content == JPEG
    assert client.get("/api/tiles/2/1/1").status_code == 404
    assert client.get("/api/tiles/2/1/2").status_code == 404
    # opened read-only
    tiles = console_of(client).tiles
    assert isinstance(tiles, MbTiles)
    with pytest.raises(sqlite3.OperationalError, match="readonly"):
        tiles._db.execute("DELETE FROM tiles")


def test_mbtiles_zoom_range_from_its_tiles_without_metadata(tmp_path: Path) -> None:
    source = open_tiles(mbtiles(tmp_path / "bare.mbtiles", fmt="jpg", zoom_meta=False))
    assert source is not None
    try:
        assert (source.min_zoom, source.max_zoom, source.format) == (1, 2, "jpg")
    finally:
        source.close()


def test_bad_tile_sources_are_refused_naming_the_setting(tmp_path: Path) -> None:
    assert open_tiles(None) is None
    assert open_tiles(Path("")) is None  # NEMESYS_TILES= (empty): none, not the cwd
    with pytest.raises(ValueError, match=r"tiles .*directory of z/x/y\.png tiles or an \.mbtiles"):
        open_tiles(tmp_path / "missing")
    with pytest.raises(ValueError, match=r"vector tiles \(pbf\) are not supported"):
        open_tiles(mbtiles(tmp_path / "vector.mbtiles", fmt="pbf"))
    broken = tmp_path / "broken.mbtiles"
    broken.write_bytes(b"not a database at all" * 100)
    with pytest.raises(ValueError, match="not a readable MBTiles file"):
        open_tiles(broken)
    empty = tmp_path / "empty"
    empty.mkdir()
    source = open_tiles(empty)
    assert source is not None and source.min_zoom is None and source.format is None
