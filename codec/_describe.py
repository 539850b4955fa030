"""The dictionary as plain data, for listings, the API and the docs."""

from __future__ import annotations

from codec._dictionary import DICTIONARY, CommandDictionary
from codec._scales import ChoiceScale

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from codec._dictionary import Pattern
    from codec._fields import Field


def describe_field(f: Field, position: int) -> dict[str, Any]:
    """One field as JSON-ready data (``position`` is 1 for j1)."""
    scale = f.scale
    out: dict[str, Any] = {
        "j": position,
        "name": f.name,
        "label": f.label,
        "unit": f.unit,
        "doc": f.doc,
        "default": f.default,
        "scale": scale.name,
        "range": scale.range_text(f.unit),
        "steps": scale.describe(),
        "error": scale.error_text(f.unit),
    }
    if isinstance(scale, ChoiceScale):
        out["kind"] = "choice"
        out["choices"] = list(scale.choices)
    else:
        out["kind"] = "count" if scale.integer else "number"
        out["min"] = scale.minimum
        out["max"] = scale.maximum
        out["codes"] = [scale.first_code, scale.first_code + len(scale.values) - 1]
        out["segments"] = [
            {"start": float(s.start), "step": float(s.step), "count": s.count}
            for s in scale.segments
        ]
        if scale.period is not None:
            out["period"] = scale.period
        if scale.max_rel_error is not None:
            out["max_rel_error"] = scale.max_rel_error
        out["max_abs_error"] = scale.max_abs_error
    return out


def describe_pattern(p: Pattern) -> dict[str, Any]:
    return {
        "id": p.id,
        "name": p.name,
        "label": p.label,
        "doc": p.doc,
        "fields": [describe_field(f, j + 1) for j, f in enumerate(p.fields)],
    }


def describe_dictionary(dictionary: CommandDictionary = DICTIONARY) -> list[dict[str, Any]]:
    """Every pattern, in ID order."""
    return [describe_pattern(p) for p in sorted(dictionary.values(), key=lambda p: p.id)]


def markdown_tables(dictionary: CommandDictionary = DICTIONARY) -> str:
    """Scales and patterns as two Markdown tables (docs/protocol.md embeds this verbatim)."""
    scales: dict[str, tuple[str, Field]] = {}
    for p in dictionary.values():
        for f in p.fields:
            scales.setdefault(f.scale.name, (f.unit, f))
    rows = [
        "| scale | unit | range | codes -> values | worst-case error |",
        "|---|---|---|---|---|",
    ]
    for name, (unit, f) in scales.items():
        s = f.scale
        rows.append(
            f"| {name} | {unit or '-'} | {s.range_text(unit)} | {s.describe()} | "
            f"{s.error_text(unit)} |"
        )
    rows += [
        "",
        "| ID | pattern | j1 | j2 | j3 | j4 | j5 | j6 |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for p in sorted(dictionary.values(), key=lambda p: p.id):
        cells = [
            f.name if f.name == f.scale.name else f"{f.name} ({f.scale.name})" for f in p.fields
        ]
        cells += ["0"] * (6 - len(cells))
        rows.append(f"| {p.id} | {p.name} | " + " | ".join(cells) + " |")
    return "\n".join(rows)
