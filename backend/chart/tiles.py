"""Optional local map tiles for the chart: a directory of ``z/x/y.png`` (``.jpg``, ``.jpeg``,
``.webp``) tiles, or an MBTiles file (SQLite; its rows are TMS, counted from the south, so
row = 2^z - 1 - y). Nothing is fetched from the network; without tiles the chart draws its
graticule alone.

An MBTiles file is opened read-only (``mode=ro`` URI), one connection shared under a lock
(the routes run in a thread pool). A tile is looked up by integer ``z``, ``x``, ``y`` only, so
no request can name a file outside the directory.
"""

from __future__ import annotations

import sqlite3
import threading
from pathlib import Path
from typing import Final
from urllib.parse import quote

__all__ = ["MAX_ZOOM", "TileSource", "open_tiles"]

#: Deepest zoom level served (Web Mercator tiles go to about 2 cm at 30).
MAX_ZOOM: Final = 30
#: Extensions of a tile directory's files, and their media types.
EXTENSIONS: Final = {".png": "png", ".jpg": "jpg", ".jpeg": "jpg", ".webp": "webp"}
MEDIA_TYPES: Final = {"png": "image/png", "jpg": "image/jpeg", "webp": "image/webp"}


def sniff(data: bytes) -> str | None:
    """The image format of a tile from its first bytes (png, jpg, webp), or None."""
    if data.startswith(b"\x89PNG\r\n\x1a\n"):
        return "png"
    if data.startswith(b"\xff\xd8\xff"):
        return "jpg"
    if data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        return "webp"
    return None


class TileSource:
    """Where tiles come from: :meth:`get` a tile; ``min_zoom``/``max_zoom``, ``format``."""

    kind: str = ""
    min_zoom: int | None = None
    max_zoom: int | None = None
    format: str | None = None

    def get(self, z: int, x: int, y: int) -> tuple[bytes, str] | None:
        """The tile's bytes and media type, or None when there is none."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the source (nothing for a directory)."""


class DirectoryTiles(TileSource):
    """A directory ``root/z/x/y.ext``; zoom levels from its numeric sub-directory names."""

    kind = "directory"

    def __init__(self, root: Path) -> None:
        self.root = root.resolve()
        zooms = sorted(
            int(p.name)
            for p in self.root.iterdir()
            if p.is_dir() and p.name.isascii() and p.name.isdigit() and int(p.name) <= MAX_ZOOM
        )
        self.min_zoom = zooms[0] if zooms else None
        self.max_zoom = zooms[-1] if zooms else None
        self.format = self._first_format(zooms)

    def _first_format(self, zooms: list[int]) -> str | None:
        for z in zooms:
            for column in (self.root / str(z)).iterdir():
                if column.is_dir():
                    for tile in column.iterdir():
                        fmt = EXTENSIONS.get(tile.suffix.lower())
                        if fmt is not None:
                            return fmt
        return None

    def get(self, z: int, x: int, y: int) -> tuple[bytes, str] | None:
        base = self.root / str(z) / str(x)
        for ext, fmt in EXTENSIONS.items():
            path = base / f"{y}{ext}"
            if path.is_file():
                # integers only name it; still, nothing resolving outside the root (a symlink)
                if not path.resolve().is_relative_to(self.root):
                    return None
                data = path.read_bytes()
                return data, MEDIA_TYPES[sniff(data) or fmt]
        return None


class MbTiles(TileSource):
    """An MBTiles 1.x file, read-only: ``tiles(zoom_level, tile_column, tile_row)`` in TMS
    rows, ``metadata(name, value)`` with ``format``, ``minzoom``, ``maxzoom``."""

    kind = "mbtiles"

    def __init__(self, path: Path) -> None:
        self.path = path.resolve()
        uri = f"file:{quote(str(self.path))}?mode=ro"
        try:
            self._db = sqlite3.connect(uri, uri=True, check_same_thread=False)
            meta = dict(self._db.execute("SELECT name, value FROM metadata").fetchall())
            zooms = self._db.execute("SELECT MIN(zoom_level), MAX(zoom_level) FROM tiles")
            low, high = zooms.fetchone()
        except sqlite3.Error as err:
            raise ValueError(f"tiles {path}: not a readable MBTiles file: {err}") from None
        self._lock = threading.Lock()
        fmt = str(meta.get("format", "")).lower().replace("jpeg", "jpg")
        if fmt in ("pbf", "mvt"):
            self._db.close()
            raise ValueError(f"tiles {path}: vector tiles ({fmt}) are not supported, only raster")
        self.format = fmt if fmt in MEDIA_TYPES else None
        self.min_zoom = _int(meta.get("minzoom"), low)
        self.max_zoom = _int(meta.get("maxzoom"), high)

    def get(self, z: int, x: int, y: int) -> tuple[bytes, str] | None:
        row = (1 << z) - 1 - y  # TMS: rows counted from the south
        with self._lock:
            found = self._db.execute(
                "SELECT tile_data FROM tiles WHERE zoom_level = ? AND tile_column = ? "
                "AND tile_row = ?",
                (z, x, row),
            ).fetchone()
        if found is None or found[0] is None:
            return None
        data = bytes(found[0])
        fmt = sniff(data) or self.format
        return (data, MEDIA_TYPES[fmt]) if fmt is not None else None

    def close(self) -> None:
        with self._lock:
            self._db.close()


def _int(value: object, fallback: object) -> int | None:
    for v in (value, fallback):
        if isinstance(v, int) or (isinstance(v, str) and v.isascii() and v.strip().isdigit()):
            return int(v)
    return None


def open_tiles(path: Path | None) -> TileSource | None:
    """The tiles of the ``tiles`` setting (None: none; an empty setting, which pydantic
    reads as ``.``, is none too, not the working directory).

    Raises:
        ValueError: the path is neither a directory nor a readable ``.mbtiles`` file (the
            message names the setting and the path).
    """
    if path is None or path == Path(""):
        return None
    if path.is_dir():
        return DirectoryTiles(path)
    if path.is_file() and path.suffix.lower() == ".mbtiles":
        return MbTiles(path)
    raise ValueError(
        f"tiles {str(path)!r}: expected a directory of z/x/y.png tiles or an .mbtiles file"
    )
