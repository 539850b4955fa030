"""Strict input: text in a request is valid Unicode, and a boolean is not a number.

**Lone surrogates.** JSON may write a UTF-16 surrogate alone (``"\\ud800"``) and Python's
parser reads it into a ``str`` that no encoder can write: echoed in a 422, logged, stored or
sent on, it raised (a 500 that also closed the keep-alive connection under the next
request). A lone surrogate is not a character (RFC 7493, I-JSON, forbids it), so the rule
is one, applied where JSON is decoded, before anything reads a field:

* REST: :func:`strict_json_body`, a dependency of the whole app, refuses a JSON body holding
  one anywhere (a value or an object's key) with a 422 whose ``loc`` names the field;
* ``/ws``: :mod:`backend.api.live` checks each control message with :func:`lone_surrogate_in`
  the same way.

**Booleans.** JSON's ``true`` is not ``1``: pydantic in lax mode, and a ``Literal[1]`` even in
strict mode, would take it as one. :data:`NotBool` refuses it where a model is not strict.

Numbers written as text are ASCII digits only: :func:`codec.number_from_text`, and
:func:`error_message` says so where pydantic reads one (a query parameter, a setting).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any, Final

from fastapi.exceptions import RequestValidationError
from pydantic import BeforeValidator
from starlette.requests import HTTPConnection, Request

from codec import ASCII_DIGITS

#: Where in a decoded JSON document: keys and list indexes from the top.
Loc = tuple[str | int, ...]

#: The type of the error, as pydantic names its own for text that is not Unicode.
UNICODE_ERROR: Final = "string_unicode"
#: A ``\u`` escape of a surrogate (D800-DFFF): only through one can an ASCII body hold one.
_SURROGATE_ESCAPE: Final = re.compile(rb"\\u[dD][89a-fA-F]")


def lone_surrogate(text: str) -> int | None:
    """The index of the first lone surrogate in ``text``, ``None`` when it is valid Unicode
    (a paired surrogate never reaches a ``str``: the JSON parser joins the pair)."""
    if text.isascii():
        return None
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as err:
        return err.start
    return None


def lone_surrogate_in(document: object) -> tuple[Loc, str, str] | None:
    """The first text in a decoded JSON ``document`` holding a lone surrogate (an object's
    keys before its values, then depth first): its place, the message saying what is wrong
    and the text itself (:func:`printable`); ``None`` when all its text is valid. Iterative:
    any depth."""
    stack: list[tuple[Loc, object]] = [((), document)]
    while stack:
        loc, node = stack.pop()
        if isinstance(node, str):
            index = lone_surrogate(node)
            if index is not None:
                return loc, surrogate_message(node, index), printable(node)
        elif isinstance(node, dict):
            for key in node:
                index = lone_surrogate(key)
                if index is not None:  # named by its own place, as pydantic names a key
                    message = "this key: " + surrogate_message(key, index)
                    return (*loc, printable(key)), message, printable(key)
            stack.extend(((*loc, key), value) for key, value in reversed(node.items()))
        elif isinstance(node, list):
            stack.extend(((*loc, i), value) for i, value in reversed(list(enumerate(node))))
    return None


def surrogate_message(text: str, index: int) -> str:
    """What the 422 says of a lone surrogate at ``index`` of ``text``."""
    escape = ascii(text[index])[1:-1]  # \\ud800
    return (
        f"text must be valid Unicode: a lone surrogate ({escape} at character {index}) is "
        "not a character; a \\uD800-\\uDFFF escape must be one half of a pair"
    )


def printable(text: str) -> str:
    """``text`` with every lone surrogate written as its escape (``\\ud800``): what an
    error message may quote of invalid text (it can be encoded; the original cannot)."""
    if lone_surrogate(text) is None:
        return text
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


async def strict_json_body(connection: HTTPConnection) -> None:
    """Refuse a JSON request body holding a lone surrogate: 422, ``loc`` ``["body", ...]``
    naming the field, type ``string_unicode``; nothing else runs (no authentication, no
    validation of the model, no handler). A dependency of the whole app: FastAPI has
    decoded the body by then (a route without a body, a websocket: nothing to check).

    An ASCII body without a ``\\uD8..``-``\\uDF..`` escape (nearly every request) costs one
    scan of its bytes; any other is walked once (:func:`lone_surrogate_in`)."""
    if not isinstance(connection, Request):
        return
    route = connection.scope.get("route")
    if getattr(route, "body_field", None) is None:
        return
    body = await connection.body()  # read once already, by FastAPI
    if not body or (body.isascii() and not _SURROGATE_ESCAPE.search(body)):
        return
    try:
        document = await connection.json()  # decoded already when FastAPI took it as JSON
    except (ValueError, RecursionError):  # not JSON: FastAPI's validation answers that
        return
    found = lone_surrogate_in(document)
    if found is not None:
        loc, message, text = found
        raise RequestValidationError(
            [{"loc": ("body", *loc), "msg": message, "type": UNICODE_ERROR, "input": text}]
        )


#: pydantic's errors of reading a number from text (a query or path parameter, a setting).
_NUMBER_PARSING: Final = frozenset({"int_parsing", "float_parsing"})


def error_message(error: Mapping[str, Any]) -> str:
    """pydantic's message of one validation error, saying the rule when the text was a
    number in other than ASCII digits (pydantic says only "unable to parse")."""
    msg = str(error.get("msg", ""))
    given = error.get("input")
    if error.get("type") in _NUMBER_PARSING and isinstance(given, str) and not given.isascii():
        return f"{msg}: {ASCII_DIGITS}"
    return msg


def _not_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError(f"a boolean is not a number: expected a number, got {str(value).lower()}")
    return value


#: ``Annotated[X, NotBool]``: ``true`` and ``false`` are refused where a number is expected.
NotBool: Final = BeforeValidator(_not_bool)
