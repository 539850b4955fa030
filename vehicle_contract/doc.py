"""``docs/vehicle.md``, written from the vehicle contract (:mod:`vehicle_contract.contract`).

The page is generated, never edited: ``scripts/gen_vehicle_doc.py`` (or
``nemesys contract --markdown``) writes it, and ``tests/vehicle_contract/test_contract.py`` fails
when the committed page differs from :func:`render_markdown`. Nothing here depends on the
clock or the machine, so a rerun gives the same bytes.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Final

from vehicle_contract.contract import (
    ACK_DEADLINE_S,
    CONTRACT_VERSION,
    CONVENTIONS,
    OBLIGATIONS,
    TIME_BASE,
    TOPICS,
    VERSION_RULE,
    Topic,
)
from vehicle_contract.payloads import SCHEMAS, required_fields

#: Where the page lives, from the repository root.
DOC_PATH: Final = Path("docs") / "vehicle.md"
#: How to write it again.
REGENERATE: Final = ".venv/bin/python scripts/gen_vehicle_doc.py"

_TITLES: Final = {
    "ack": "The acknowledgement (`/nemesys/mission`)",
    "status": "The status (`/nemesys/status`)",
    "datum": "The datum (`/nemesys/datum`)",
}


def _type_text(prop: dict[str, Any]) -> str:
    """A property's type in words: ``number or null``, ``one of a, b``, ``command or null``."""
    if "anyOf" in prop:
        return " or ".join(_type_text(p) for p in prop["anyOf"])
    if "$ref" in prop:
        return str(prop["$ref"]).rsplit("/", 1)[-1].replace("_", " ")
    if "enum" in prop:
        return "one of " + ", ".join("null" if v is None else f"`{v}`" for v in prop["enum"])
    kind = prop.get("type", "any")
    text = " or ".join(kind) if isinstance(kind, list) else str(kind)
    bounds = [f"{k} {prop[k]:g}" for k in ("minimum", "maximum") if k in prop]
    return f"{text} ({', '.join(bounds)})" if bounds else text


def _json(value: Any, indent: int = 0, lead: int = 0, width: int = 100) -> str:
    """``value`` as indented JSON: an object or list on one line where it fits (``lead``:
    characters before it on its line), a list of plain values packed into full lines."""
    flat = json.dumps(value, ensure_ascii=False)
    if indent + lead + len(flat) <= width or not isinstance(value, dict | list) or not value:
        return flat
    pad = " " * (indent + 2)
    if isinstance(value, dict):
        items = []
        for k, v in value.items():
            key = f"{json.dumps(k)}: "
            items.append(f"{pad}{key}{_json(v, indent + 2, len(key), width)}")
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    if not any(isinstance(v, dict | list) for v in value):
        rows: list[str] = []
        for word in (json.dumps(v, ensure_ascii=False) for v in value):
            if rows and len(pad) + len(rows[-1]) + len(word) + 2 <= width:
                rows[-1] += f", {word}"
            else:
                rows.append(word)
        items = [pad + row for row in rows]
    else:
        items = [pad + _json(v, indent + 2, 0, width) for v in value]
    return "[\n" + ",\n".join(items) + "\n" + " " * indent + "]"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _topic_row(t: Topic) -> str:
    q = t.qos
    qos = f"{q.reliability}, {q.durability}, depth {q.depth}"
    cells = (
        f"`{t.name}`",
        f"`{t.type}`",
        str(t.direction),
        qos,
        t.rate,
        f"`{t.frame_id}`" if t.frame_id else "none",
        "yes" if t.required else "no",
    )
    return "| " + " | ".join(_cell(c) for c in cells) + " |"


def _schema_section(name: str, schema: dict[str, Any]) -> list[str]:
    required = required_fields(schema)
    lines = [
        f"## {_TITLES[name]}",
        "",
        f"{schema['description'].capitalize()}. Schema `{name}`, JSON Schema draft 2020-12. "
        f"Required fields (the console reads them): {', '.join(f'`{f}`' for f in required)}. "
        "Other fields are optional; fields not listed are allowed (a later minor version may "
        "add them).",
        "",
        "| field | type | required | meaning |",
        "|---|---|---|---|",
    ]
    for field, prop in schema["properties"].items():
        cells = (
            f"`{field}`",
            _type_text(prop),
            "yes" if field in required else "no",
            prop.get("description", ""),
        )
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    lines += ["", "```json", _json(schema), "```", ""]
    return lines


def render_markdown() -> str:
    """The whole page."""
    lines = [
        "# The vehicle contract",
        "",
        "<!-- Generated from vehicle_contract/contract.py: do not edit. Change the contract, then"
        " run",
        f"     {REGENERATE} -->",
        "",
        "What the NemeSys console and a NemeSys vehicle (the simulator, `nemesys sim`, or a real",
        "ROS 2 vehicle behind `rosbridge_server`) exchange. `nemesys contract` prints it as",
        "JSON; `nemesys vehicle-check ws://HOST:PORT` checks a running vehicle against it.",
        "",
        "The acknowledgement and the status travel as JSON in `std_msgs/String`: the contract's",
        "form, which needs no generated code on either side. Their typed forms",
        "(`nemesys_msgs/msg/Ack`, `Status`, `Command`: the interface package `ros2/nemesys_msgs`)",
        "are what the console's dive exports carry (docs/foxglove.md) and what a vehicle may",
        "publish natively beside them; they are not contract topics.",
        "",
        f"**Version {CONTRACT_VERSION}.** The version follows {VERSION_RULE}",
        "",
        "## Time base",
        "",
        "| what | how |",
        "|---|---|",
        *(f"| {k} | {_cell(v)} |" for k, v in TIME_BASE.items()),
        "",
        "## Conventions",
        "",
        "| what | how |",
        "|---|---|",
        *(f"| {k} | {_cell(v)} |" for k, v in CONVENTIONS.items()),
        "",
        "## Topics",
        "",
        "Types are given in the ROS 2 spelling; `pkg/Name` denotes the same type. The names are",
        "those of a vehicle without a namespace; under namespace `auv1` each is",
        "`/auv1/nemesys/...`.",
        "",
        "| topic | type | direction | QoS (reliability, durability, history depth) | rate "
        "| frame_id | required |",
        "|---|---|---|---|---|---|---|",
        *(_topic_row(t) for t in TOPICS),
        "",
        *(f"- `{t.name}`: {t.description}." for t in TOPICS),
        "",
        "## What a vehicle must do",
        "",
        *(f"{i}. {text}" for i, text in enumerate(OBLIGATIONS, start=1)),
        "",
    ]
    for name, schema in SCHEMAS.items():
        lines += _schema_section(name, schema)
    lines += [
        "## Checking a vehicle",
        "",
        "`nemesys vehicle-check ws://HOST:PORT [--modem TARGET] [--namespace NS] [--json]",
        "[--timeout S] [--window S]` connects as the console does and prints one row per check",
        "(pass, fail or skipped, and why); a vehicle under a namespace is checked on",
        "`/NS/nemesys/...` (default `NEMESYS_VEHICLE_NAMESPACE`), its nodes found by the topics",
        "they publish and subscribe, whatever their names. The graph is read by the console's",
        "own rule: each contract topic",
        "with its type (`/rosapi/topics`) and the node at the vehicle's end of it",
        "(`/rosapi/publishers`, and `/rosapi/subscribers` for the frame topic), leaving out",
        "rosbridge's own node, which subscribes and publishes for its clients (so a topic an",
        "observer subscribes to exists without the vehicle); the onboard agent runs when",
        "`/nemesys/mission` and `/nemesys/status` have such a publisher. Then the pose rate and",
        "age, the status rate and schema, and the acknowledgement path: a deliberately",
        "malformed frame (preamble and delimiter right, its codeword 3 bits from the all-zero",
        "codeword, beyond BCH's reach) must come back `rejected`, reason `uncorrectable`, its",
        f"round trip within the ack deadline ({ACK_DEADLINE_S:g} s), with the active command",
        "unchanged; it runs on a fresh vehicle too. While",
        "a command runs, it is also re-sent once and must come back `duplicate: true`. Those are",
        "the only frames the check sends. A vehicle that takes frames over its own ME receiver",
        "(no frame subscriber but rosbridge's) fails that row unless `--modem tcp://HOST:PORT`",
        "(or `serial:///dev/...`) sends the probe through the ME modem; its acknowledgement is",
        "still read over rosbridge. Exit status 0 when no check failed, 1 otherwise, 2 for bad",
        "usage.",
        "",
    ]
    return "\n".join(lines)


def write(root: Path) -> Path:
    """Write the page under the repository ``root``; returns its path."""
    path = root / DOC_PATH
    path.write_text(render_markdown(), encoding="utf-8")
    return path
