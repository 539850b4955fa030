"""``docs/live.md``, written from the ``/ws`` message models (:mod:`backend.api.schemas.live`).

The page is generated, never edited: ``scripts/gen_live_doc.py`` writes it, and
``tests/backend/test_live_messages.py`` fails when the committed page differs from
:func:`render_markdown`. It lists every message (its ``type``, direction, model and
fields, from the models' JSON Schema) and ends with the JSON Schema of the union
(:data:`backend.api.schemas.live.LiveMessage`). Nothing here depends on the clock or the
machine, so a rerun gives the same bytes.
"""

from __future__ import annotations

import inspect
import json
from pathlib import Path
from typing import Any, Final

from pydantic import BaseModel, TypeAdapter

from backend.api.schemas.live import (
    ClientMessage,
    LiveMessage,
    ServerMessage,
    message_models,
    type_of,
)
from backend.messages import News

#: Where the page lives, from the repository root.
DOC_PATH: Final = Path("docs") / "live.md"
#: How to write it again.
REGENERATE: Final = ".venv/bin/python scripts/gen_live_doc.py"

_INTRO: Final = """\
The console's live websocket: what it pushes to every page (the news), and the page's own
control messages with their answers. Every message is one JSON object (a text frame) whose
`type` names it. A browser page from another origin is refused at the handshake (403). A page
sends `auth` with the operator token on every (re)connection; without it the connection stays
open for the news, read-only, and `surface` and `send` are refused. `send` is checked as
`POST /api/commands` checks it (the same fields and rules) and `surface` as
`POST /api/surface`: both go through the command service, and a refusal is an `error`
naming the field, with the HTTP status REST gives the same refusal. A control message over
4096 bytes, nested deeper than 32, not JSON, with `NaN` or `Infinity`, or in a binary frame
is an `error` too; the connection stays open."""


def _direction(model: type[BaseModel]) -> str:
    if model in message_models(ClientMessage):
        return "page -> console"
    if model in message_models(News):
        return "console -> every page"
    return "console -> the page that asked"


def _markdown(text: str) -> str:
    """A docstring's text on one line, its reStructuredText literals as Markdown's."""
    return " ".join(text.split()).replace("``", "`")


def _doc(model: type[BaseModel]) -> str:
    """The model's docstring on one line."""
    return _markdown(inspect.getdoc(model) or "")


def _untitled(schema: Any, names: bool = False) -> Any:
    """The schema without pydantic's generated ``title`` keywords (the names say it)."""
    if isinstance(schema, list):
        return [_untitled(s) for s in schema]
    if not isinstance(schema, dict):
        return schema
    return {
        k: _untitled(v, names=k in ("properties", "$defs") and not names)
        for k, v in schema.items()
        if names or k != "title"
    }


def live_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of every ``/ws`` message: the union, discriminated by
    ``type``, as the console writes and reads them (serialisation's view of the models)."""
    schema: dict[str, Any] = TypeAdapter(LiveMessage).json_schema(mode="serialization")
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **_untitled(schema)}


def _type_text(prop: dict[str, Any]) -> str:
    """A property's type in words: ``number or null``, ``CommandRecord``, ``"telemetry"``."""
    if "anyOf" in prop:
        return " or ".join(_type_text(p) for p in prop["anyOf"])
    if "$ref" in prop:
        return str(prop["$ref"]).rsplit("/", 1)[-1]
    if "const" in prop:
        return json.dumps(prop["const"])
    if "enum" in prop:
        return "one of " + ", ".join(json.dumps(v) for v in prop["enum"])
    kind = prop.get("type", "any")
    if kind == "array" and "items" in prop:
        return f"array of {_type_text(prop['items'])}"
    if kind == "object" and isinstance(prop.get("additionalProperties"), dict):
        return f"object of {_type_text(prop['additionalProperties'])}"
    return str(kind)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _message_section(model: type[BaseModel], schema: dict[str, Any]) -> list[str]:
    lines = [
        f"### `{type_of(model)}` ({_direction(model)})",
        "",
        f"{_doc(model)} Model `{model.__name__}`.",
        "",
        "| field | type | required | meaning |",
        "|---|---|---|---|",
    ]
    required = schema.get("required", [])
    for field, prop in schema["properties"].items():
        cells = (
            f"`{field}`",
            _type_text(prop),
            "yes" if field in required else "no",
            _markdown(prop.get("description", "")),
        )
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return [*lines, ""]


def render_markdown() -> str:
    """The whole page."""
    schema = live_schema()
    models = message_models(ServerMessage) + message_models(ClientMessage)
    lines = [
        "# The live websocket `/ws`",
        "",
        "<!-- Generated from backend/api/schemas/live.py and backend/messages.py: do not edit."
        " Change the models, then run",
        f"     {REGENERATE} -->",
        "",
        _INTRO,
        "",
        "## The messages",
        "",
        "| `type` | direction | model | what |",
        "|---|---|---|---|",
    ]
    for model in models:
        first = _doc(model).split(". ")[0].rstrip(".")
        cells = (f"`{type_of(model)}`", _direction(model), f"`{model.__name__}`", first)
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    lines += ["", "## Each message", ""]
    for model in models:
        lines += _message_section(model, schema["$defs"][model.__name__])
    lines += [
        "## The JSON Schema",
        "",
        "Every message, either way: one schema, the union discriminated by `type` (the shapes",
        "they share, such as the command record, are under `$defs`).",
        "",
        "```json",
        json.dumps(schema, indent=2, ensure_ascii=False),
        "```",
        "",
    ]
    return "\n".join(lines)


def write(root: Path) -> Path:
    """Write the page under the repository ``root``; returns its path."""
    path = root / DOC_PATH
    path.write_text(render_markdown(), encoding="utf-8")
    return path


__all__ = ["DOC_PATH", "REGENERATE", "live_schema", "render_markdown", "write"]
