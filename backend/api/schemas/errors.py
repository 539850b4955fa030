"""Error bodies, and the ``responses`` each route declares for its errors.

Every error is JSON ``{"detail": ...}``: a sentence for most, FastAPI's list of validation
errors for a 422, and a structured object where the handler gives one (a send's limit
violations, a rejected frame's reason).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from pydantic import BaseModel, Field

from backend.api.schemas.common import LimitViolation


class ErrorDetail(BaseModel):
    """An error in words."""

    detail: str


class ValidationErrorItem(BaseModel):
    """One validation error: ``loc`` names the parameter at fault, ``msg`` what is allowed."""

    loc: list[str | int]
    msg: str
    type: str
    input: Any = None
    ctx: dict[str, Any] | None = None


class ValidationErrorResponse(BaseModel):
    """Validation errors (FastAPI's shape); the codec's and planner's refusals use it too."""

    detail: list[ValidationErrorItem]


class LimitViolations(BaseModel):
    message: str
    violations: list[LimitViolation]


class LimitViolationError(BaseModel):
    """A send refused for its limits: 409 for overridable ones (send again with
    ``override``), 422 for those no operator can override (the depth rating)."""

    detail: LimitViolations


class FrameRejection(BaseModel):
    reason: str = Field(description="the codec's reason, e.g. crc_mismatch")
    message: str
    field: str | None


class DecodeFailure(BaseModel):
    """A frame that does not decode, with the codec's reason."""

    detail: FrameRejection


#: What each error status means, unless a route says more.
ERROR_TEXT: Mapping[int, str] = {
    401: "operator token missing (Authorization: Bearer <token>, or X-Nemesys-Token)",
    403: "wrong operator token",
    404: "no such item",
    409: "conflicts with the console's state",
    413: "request body too large",
    422: "invalid input; loc names the parameter at fault",
    429: "too many transmissions in the last minute; retry after Retry-After seconds",
    503: "the console cannot take commands now (starting, or the mission log cannot be "
    "written); nothing was sent",
    504: "a console without a transmitter (target relay): no console holding the transmitter "
    "took the command within relay_wait_s; it was withdrawn, nothing was sent",
}
_HEADERS: Mapping[int, dict[str, Any]] = {
    401: {"WWW-Authenticate": {"description": "Bearer", "schema": {"type": "string"}}},
    429: {
        "Retry-After": {
            "description": "seconds until a transmission is allowed again",
            "schema": {"type": "integer"},
        }
    },
    503: {
        "Retry-After": {
            "description": "seconds to wait before trying again (when the log cannot be written)",
            "schema": {"type": "integer"},
        }
    },
}
#: The errors of every call that needs the operator's token.
OPERATOR = (401, 403)


def errors(
    codes: Iterable[int],
    models: Mapping[int, Any] | None = None,
    why: Mapping[int, str] | None = None,
) -> dict[int | str, dict[str, Any]]:
    """The ``responses`` of a route for its error ``codes``: each with its model
    (``{"detail": str}``, validation errors for 422, or ``models[code]``) and a description
    (``why[code]`` or the default)."""
    out: dict[int | str, dict[str, Any]] = {}
    for code in sorted(set(codes)):
        default = ValidationErrorResponse if code == 422 else ErrorDetail
        entry: dict[str, Any] = {
            "model": (models or {}).get(code, default),
            "description": (why or {}).get(code, ERROR_TEXT[code]),
        }
        if code in _HEADERS:
            entry["headers"] = _HEADERS[code]
        out[code] = entry
    return out
