"""The OpenAPI document's security: the operator token's two schemes, required by every
operation that needs it.

The token travels as ``Authorization: Bearer <token>`` or in the ``X-Nemesys-Token`` header
(:func:`backend.api.deps.require_operator` reads either). An operation requires one of the two
(OpenAPI: a list of alternatives) exactly when it declares the token's 401 (its route lists
``backend.api.schemas.OPERATOR`` among its errors); ``tests/backend/test_openapi.py`` checks
that every operation answering 401 without the token declares it, and no other.
"""

from __future__ import annotations

from typing import Any, Final

from fastapi import FastAPI

#: The schemes, as ``components.securitySchemes``.
SECURITY_SCHEMES: Final[dict[str, dict[str, Any]]] = {
    "bearerAuth": {
        "type": "http",
        "scheme": "bearer",
        "description": "the operator token (nemesys console prints it): "
        "Authorization: Bearer <token>",
    },
    "tokenHeader": {
        "type": "apiKey",
        "in": "header",
        "name": "X-Nemesys-Token",
        "description": "the operator token in a header of its own",
    },
}
#: An operator operation's requirement: either scheme.
OPERATOR_SECURITY: Final[list[dict[str, list[str]]]] = [{name: []} for name in SECURITY_SCHEMES]


def add_security(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` (the app's OpenAPI document) with the schemes and the requirements."""
    schema.setdefault("components", {}).setdefault("securitySchemes", {}).update(SECURITY_SCHEMES)
    for operations in schema.get("paths", {}).values():
        for operation in operations.values():
            if isinstance(operation, dict) and "401" in operation.get("responses", {}):
                operation["security"] = list(OPERATOR_SECURITY)
    return schema


def security_schemes(app: FastAPI) -> None:
    """Make ``app.openapi()`` declare the token's schemes and require them on every operator
    operation. Call once, in ``create_app``. (FastAPI builds the document once and again
    only when routes change; adding the security to it is idempotent.)"""
    build = app.openapi

    def openapi() -> dict[str, Any]:
        return add_security(build())

    app.openapi = openapi  # type: ignore[method-assign]
