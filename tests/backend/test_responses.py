"""backend/api/responses.py: the large documents' renderer is JSON, byte for byte what the
page parses, with non-finite numbers as null (never invalid JSON, never a 500), and a model
as the API serialises its models."""

from __future__ import annotations

import json
import math

from pydantic import BaseModel, Field

from backend.api.responses import DocResponse


def test_renders_the_same_json_as_the_standard_library() -> None:
    doc = {
        "path": {"x_m": [0.0, 1.25, -3.5e-7, 1e21], "body_start": 3, "repeats": False},
        "text": "29°31.896'N — «quoted»",
        "diff": None,
        "nested": [{"a": 1}, [], {}],
    }
    body = bytes(DocResponse(doc).body)
    assert json.loads(body) == doc
    assert body.decode("utf-8").find("29°31.896'N") > 0  # UTF-8 as is, not escaped


def test_non_finite_numbers_become_null() -> None:
    body = bytes(DocResponse({"a": math.nan, "b": [math.inf, -math.inf, 1.5]}).body)
    assert json.loads(body) == {"a": None, "b": [None, None, 1.5]}
    assert b"NaN" not in body and b"Infinity" not in body


class _Doc(BaseModel):
    from_: float = Field(alias="from")
    note: str | None = None
    x_m: list[float]


def test_a_model_renders_as_the_api_serialises_models() -> None:
    """By alias, only the fields it was given, non-finite numbers null."""
    doc = _Doc.model_validate({"from": 1.5, "x_m": [math.nan, 2.0]})
    body = bytes(DocResponse(doc).body)
    assert json.loads(body) == {"from": 1.5, "x_m": [None, 2.0]}
    given = _Doc.model_validate({"from": 1, "note": None, "x_m": []})
    assert json.loads(bytes(DocResponse(given).body)) == {"from": 1.0, "note": None, "x_m": []}
