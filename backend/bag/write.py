"""Writing a dive's messages: an MCAP file (``mcap_ros2``'s writer: profile ros2, CDR, zstd
chunks with message indexes and a summary, so ``ros2 bag play``, Foxglove and PlotJuggler
seek in it), a rosbag2 directory (rosbags' writer: ``metadata.yaml`` beside one MCAP storage
file), or MCAP bytes as they are made (the API's streamed download).

Memory stays flat: a message is encoded and handed to the writer as it comes; the writers keep
one chunk (:data:`CHUNK_BYTES`) and per chunk a few index entries. A file is never left half
written: it is written under a temporary name beside its place and renamed into it once
complete (a directory likewise); an existing one is replaced only when asked (``force``).
"""

from __future__ import annotations

import os
import secrets
import shutil
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Final

import numpy as np
from mcap.records import Schema
from mcap.well_known import SchemaEncoding
from mcap.writer import CompressionType
from mcap_ros2.writer import Writer as McapRos2Writer
from rosbags.interfaces import Nodetype
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.rosbag2 import Writer as Rosbag2Writer
from rosbags.typesys.store import Typestore

from backend.bag.dive import Message
from backend.bag.msgdefs import definition, typestore

#: The MCAP chunk size (bytes, before compression): the writer's memory, and the unit a reader
#: seeks by.
CHUNK_BYTES: Final = 1024 * 1024
#: The streamed download hands on what the writer made once this much is waiting (bytes).
STREAM_BYTES: Final = 256 * 1024
#: Messages between two progress reports.
PROGRESS_EVERY: Final = 5000

#: Progress: messages written so far, and the expected total.
Progress = Callable[[int, int], None]


class ExportExists(FileExistsError):
    """The output exists and replacing it was not asked for (or it is not an export)."""


@dataclass
class Written:
    """What an export wrote: messages per topic, bytes, seconds."""

    path: Path | None = None
    topics: dict[str, int] = field(default_factory=dict)
    size_bytes: int = 0
    seconds: float = 0.0

    @property
    def messages(self) -> int:
        return sum(self.topics.values())


# --- the two writers --------------------------------------------------------------------


class McapSink:
    """Messages into an MCAP stream (``output``: anything with ``write``, ``tell``, ``flush``)
    through ``mcap_ros2``'s writer, a schema per type registered at its first message."""

    def __init__(self, output: IO[bytes], metadata: Mapping[str, str]) -> None:
        self._writer = McapRos2Writer(
            output, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD
        )
        self._writer.add_metadata("nemesys_dive", dict(metadata))
        self._schemas: dict[str, Schema] = {}

    def write(self, message: Message) -> None:
        ros_type = message.topic.type
        schema = self._schemas.get(ros_type)
        if schema is None:
            schema = self._writer.register_msgdef(ros_type, definition(ros_type))
            assert schema.encoding == SchemaEncoding.ROS2
            self._schemas[ros_type] = schema
        self._writer.write_message(
            message.topic.name, schema, message.msg, log_time=message.log_time_ns
        )

    def finish(self) -> None:
        """The summary (schemas, channels, statistics, chunk indexes) and the footer."""
        self._writer.finish()  # type: ignore[no-untyped-call]  # mcap_ros2 leaves it unannotated


_NUMPY: Final = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}


def rosbags_message(store: Typestore, ros_type: str, fields: Mapping[str, Any]) -> object:
    """A message dict (:mod:`backend.bag.messages`) as rosbags' class of ``ros_type``: nested
    messages made in turn, arrays of numbers as numpy arrays (rosbags' form)."""
    _, defs = store.fielddefs[ros_type]
    args = {name: _field(store, desc, fields[name]) for name, desc in defs}
    return store.types[ros_type](**args)


def _field(store: Typestore, desc: Any, value: Any) -> Any:
    node, detail = desc
    if node == Nodetype.NAME:
        return rosbags_message(store, detail, value)
    if node == Nodetype.BASE:
        return value
    item, _size = detail
    if item[0] == Nodetype.BASE and item[1][0] != "string":
        return np.array(value, dtype=_NUMPY[item[1][0]])
    return [_field(store, item, v) for v in value]


class Rosbag2Sink:
    """Messages into a new rosbag2 directory ``path`` (rosbags' writer, version 9, one MCAP
    storage file with zstd chunks, as ``ros2 bag record --storage mcap`` makes with its
    ``zstd_fast`` preset), each encoded by rosbags' own CDR serialiser."""

    def __init__(self, path: Path, metadata: Mapping[str, str]) -> None:
        self._store = typestore()
        self._writer = Rosbag2Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        for key, value in metadata.items():
            self._writer.set_custom_data(f"nemesys.{key}", value)
        self._writer.open()
        self._connections: dict[str, Any] = {}

    def write(self, message: Message) -> None:
        topic = message.topic
        connection = self._connections.get(topic.name)
        if connection is None:
            connection = self._writer.add_connection(topic.name, topic.type, typestore=self._store)
            self._connections[topic.name] = connection
        data = self._store.serialize_cdr(
            rosbags_message(self._store, topic.type, message.msg), topic.type
        )
        self._writer.write(connection, message.log_time_ns, data)

    def finish(self) -> None:
        """The storage file's summary, then ``metadata.yaml``."""
        self._writer.close()


def _drain(
    messages: Iterable[Message],
    sink: McapSink | Rosbag2Sink,
    written: Written,
    expected: int,
    progress: Progress | None,
) -> None:
    for n, message in enumerate(messages, start=1):
        sink.write(message)
        written.topics[message.topic.name] = written.topics.get(message.topic.name, 0) + 1
        if progress is not None and n % PROGRESS_EVERY == 0:
            progress(n, max(n, expected))
    sink.finish()
    if progress is not None:
        progress(written.messages, written.messages)


# --- files: under a temporary name, renamed when complete ---------------------------------


def _check_output(path: Path, force: bool, *, directory: bool) -> None:
    """Raises :class:`ExportExists` or :class:`FileNotFoundError` naming ``path``."""
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path.parent} is not a directory: cannot write {path} there")
    if not path.exists() and not path.is_symlink():
        return
    if not force:
        raise ExportExists(f"{path} exists: give --force to replace it")
    if directory and (not path.is_dir() or not (path / "metadata.yaml").is_file()):
        raise ExportExists(
            f"{path} exists and is not a rosbag2 directory (no metadata.yaml): not replaced"
        )
    if not directory and path.is_dir():
        raise ExportExists(f"{path} is a directory: not replaced by an MCAP file")


def write_mcap_file(
    path: Path,
    messages: Iterable[Message],
    metadata: Mapping[str, str],
    *,
    force: bool = False,
    expected: int = 0,
    progress: Progress | None = None,
) -> Written:
    """``messages`` as the MCAP file ``path`` (see the module's docstring).

    Raises:
        ExportExists: ``path`` exists and ``force`` is false.
        FileNotFoundError: its directory does not exist.
    """
    _check_output(path, force, directory=False)
    started = time.perf_counter()
    written = Written(path)
    temp = path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}.partial")
    try:
        with temp.open("xb") as out:  # the umask's modes, as any file the user writes
            _drain(messages, McapSink(out, metadata), written, expected, progress)
            out.flush()
            os.fsync(out.fileno())
        os.replace(temp, path)
    except BaseException:
        temp.unlink(missing_ok=True)
        raise
    written.size_bytes = path.stat().st_size
    written.seconds = time.perf_counter() - started
    return written


def write_rosbag2_dir(
    path: Path,
    messages: Iterable[Message],
    metadata: Mapping[str, str],
    *,
    force: bool = False,
    expected: int = 0,
    progress: Progress | None = None,
) -> Written:
    """``messages`` as the rosbag2 directory ``path`` (``metadata.yaml`` and
    ``<name>.mcap``), made in a temporary directory beside it and renamed into place.

    Raises:
        ExportExists: ``path`` exists and ``force`` is false, or it is not a rosbag2 directory.
        FileNotFoundError: its parent directory does not exist.
    """
    _check_output(path, force, directory=True)
    started = time.perf_counter()
    written = Written(path)
    work = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.", suffix=".partial"))
    try:
        bag = work / path.name  # rosbags names the storage file after its directory
        _drain(messages, Rosbag2Sink(bag, metadata), written, expected, progress)
        if path.exists():  # force, checked above: the old one goes once the new one is whole
            old = work / "replaced"
            path.rename(old)
            try:
                bag.rename(path)
            except BaseException:
                old.rename(path)  # put back
                raise
        else:
            bag.rename(path)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    written.size_bytes = sum(f.stat().st_size for f in path.iterdir() if f.is_file())
    written.seconds = time.perf_counter() - started
    return written


# --- bytes as they are made (the streamed download) ---------------------------------------


class _Pipe:
    """A write-only stream that keeps what was written until taken: the MCAP writer's output
    (it needs ``tell``) on its way to an HTTP response."""

    def __init__(self) -> None:
        self._parts: list[bytes] = []
        self.pending = 0
        self._offset = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        chunk = bytes(data)
        self._parts.append(chunk)
        self.pending += len(chunk)
        self._offset += len(chunk)
        return len(chunk)

    def tell(self) -> int:
        return self._offset

    def flush(self) -> None:
        """Nothing to flush: the bytes wait for :meth:`take`."""

    def take(self) -> bytes:
        out = b"".join(self._parts)
        self._parts.clear()
        self.pending = 0
        return out


def mcap_bytes(messages: Iterable[Message], metadata: Mapping[str, str]) -> Iterator[bytes]:
    """``messages`` as MCAP, a piece at a time (at least :data:`STREAM_BYTES` but the last)."""
    pipe = _Pipe()
    sink = McapSink(pipe, metadata)  # type: ignore[arg-type]  # a stream as far as MCAP needs
    for message in messages:
        sink.write(message)
        if pipe.pending >= STREAM_BYTES:
            yield pipe.take()
    sink.finish()
    yield pipe.take()
