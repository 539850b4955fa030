"""The live view's channels (backend/foxglove_live/channels.py): the list docs/foxglove.md
gives (and, with a fleet, each vehicle's), the schemas the JSON channels are advertised with,
and the track's bound."""

from __future__ import annotations

import json
import logging
import re
from pathlib import Path
from typing import Any

import foxglove
import pytest
from foxglove.messages import LogLevel, Pose
from pydantic import BaseModel

from backend.foxglove_live.channels import (
    CHANNELS,
    FRAMES,
    MODELS,
    PER_VEHICLE,
    SCHEMA_PREFIX,
    Channels,
    channel_specs,
    json_schema,
)
from backend.foxglove_live.publish import MAX_TRACK_POSES, Trail, level_of

DOC = Path(__file__).resolve().parents[3] / "docs" / "foxglove.md"
_ROW = re.compile(r"^\| `(/[^`]*)` \| `([^`]+)` \| (.+) \|$")


def documented_channels(doc: Path = DOC, part: str = "Channels") -> dict[str, str]:
    """topic -> schema name, as the table of the "Live" section's ``part`` of
    docs/foxglove.md lists them ("Channels"; "A fleet": each vehicle's, ``/<name>/...``)."""
    text = doc.read_text(encoding="utf-8")
    live = text.split("\n## Live\n", 1)[1].split("\n## ", 1)[0]
    section = live.split(f"\n### {part}\n", 1)[1].split("\n### ", 1)[0]
    rows = [m for line in section.splitlines() if (m := _ROW.match(line))]
    return {m.group(1): m.group(2) for m in rows}


def test_the_doc_lists_every_channel_with_its_schema_once() -> None:
    documented = documented_channels()
    assert documented == {c.topic: c.schema for c in CHANNELS}
    assert len(CHANNELS) == len({c.topic for c in CHANNELS})


def test_the_doc_lists_a_fleets_channels_of_each_vehicle_and_its_frames() -> None:
    documented = documented_channels(part="A fleet")
    own = {f"/<name>{c.topic}": c.schema for c in PER_VEHICLE}
    assert documented == {**own, FRAMES.topic: FRAMES.schema}


@pytest.mark.parametrize("vehicles", [(), ("auv1", "alpha")])
def test_the_channels_made_are_the_listed_ones(vehicles: tuple[str, ...]) -> None:
    channels = Channels(foxglove.Context(), vehicles)
    specs = channel_specs(vehicles)
    try:
        made = {**channels.typed, **channels.json}
        assert {topic: ch.schema_name() for topic, ch in made.items()} == {
            c.topic: c.schema for c in specs
        }
        encodings = {topic: ch.message_encoding for topic, ch in made.items()}
        json_topics = {t for t, e in encodings.items() if e == "json"}
        assert json_topics == {c.topic for c in specs if c.schema.startswith(SCHEMA_PREFIX)}
        assert {e for t, e in encodings.items() if t not in json_topics} == {"protobuf"}
    finally:
        channels.close()


def test_a_fleets_channels_are_the_shared_ones_each_vehicles_own_and_their_frames() -> None:
    specs = {c.topic: c.schema for c in channel_specs(("auv1", "alpha"))}
    assert channel_specs(()) == CHANNELS  # no fleet: as they always were
    shared = {c.topic: c.schema for c in CHANNELS if c not in PER_VEHICLE}
    assert "/paths/active" in shared and "/vehicle/pose" not in shared
    own = {f"/{n}{c.topic}": c.schema for n in ("auv1", "alpha") for c in PER_VEHICLE}
    assert specs == {**shared, **own, "/tf": "foxglove.FrameTransforms"}
    assert specs["/alpha/belief"] == "nemesys.Belief"


def _refs(node: Any) -> list[str]:
    if isinstance(node, dict):
        return [node["$ref"]] if "$ref" in node else [r for v in node.values() for r in _refs(v)]
    if isinstance(node, list):
        return [r for v in node for r in _refs(v)]
    return []


@pytest.mark.parametrize("topic", sorted(MODELS))
def test_json_schemas_are_the_models_with_their_refs_inlined(topic: str) -> None:
    model = MODELS[topic]
    schema = json_schema(model, SCHEMA_PREFIX + model.__name__)
    assert schema["type"] == "object" and schema["title"] == f"nemesys.{model.__name__}"
    assert _refs(schema) == [] and "$defs" not in schema
    original = model.model_json_schema(by_alias=True, mode="serialization")
    assert set(schema["properties"]) == set(original["properties"])
    assert schema.get("required") == original.get("required")
    json.dumps(schema)  # JSON as it is advertised


def test_an_inlined_ref_keeps_the_referenced_shape() -> None:
    schema = json_schema(MODELS["/belief"], "x")
    position = schema["properties"]["position"]
    assert position["type"] == "object" and "sigma_m" in position["properties"]


def test_a_model_that_refers_to_itself_cannot_be_inlined() -> None:
    class Node(BaseModel):
        children: list[Node]

    with pytest.raises(ValueError, match="Node refers to itself"):
        json_schema(Node, "node")


def test_the_track_keeps_a_pose_a_second_and_thins_itself_past_its_bound() -> None:
    trail = Trail(1.0)
    assert trail.add(0.0, Pose())
    assert not trail.add(0.5, Pose())  # within the second
    assert trail.add(1.0, Pose())
    for k in range(2, MAX_TRACK_POSES + 1):
        trail.add(float(k), Pose())
    assert len(trail.poses) == MAX_TRACK_POSES // 2 + 1  # thinned at MAX + 1
    assert trail.interval_s == 2.0
    times = [t for t, _ in trail.poses]
    assert times[0] == 0.0 and times == sorted(times)
    assert not trail.add(times[-1] + 1.5, Pose())  # the interval doubled
    trail.clear()
    assert trail.poses == [] and trail.interval_s == 1.0


@pytest.mark.parametrize(
    ("levelno", "level"),
    [
        (logging.DEBUG, LogLevel.Debug),
        (logging.INFO, LogLevel.Info),
        (logging.WARNING + 5, LogLevel.Warning),
        (logging.ERROR, LogLevel.Error),
        (logging.CRITICAL, LogLevel.Fatal),
        (5, LogLevel.Unknown),
    ],
)
def test_python_log_levels_as_foxgloves(levelno: int, level: LogLevel) -> None:
    assert level_of(levelno) == level
