"""The console's reading of a pattern's name or ID (:meth:`CommandDictionary.lookup`).

Loaded on first use, like the rest of the encode side: the vehicle decodes pattern IDs and
never looks a name up. It imports no dictionary module at run time, so the dictionary can call
it without a circle.
"""

from __future__ import annotations

from codec._errors import EncodeError

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec._dictionary import CommandDictionary, Pattern


#: What :meth:`CommandDictionary.lookup` strips around a name, and the most digits it reads
#: as an ID (leading zeros included; ``int`` is never given thousands of digits).
_ASCII_SPACE = " \t\r\n\f\v"
_MAX_ID_DIGITS = 8
#: Longest quote of an unknown pattern in the error message.
_MAX_SHOWN = 40


def lookup_pattern(dictionary: CommandDictionary, pattern: str | int) -> Pattern:
    """:meth:`CommandDictionary.lookup`: the pattern of ``dictionary`` that ``pattern`` names.

    Raises:
        EncodeError: no such pattern.
    """
    found: Pattern | None = None
    if isinstance(pattern, bool):
        found = None
    elif isinstance(pattern, int):
        found = dictionary.by_id(pattern)
    elif isinstance(pattern, str) and pattern.isascii():
        key = pattern.strip(_ASCII_SPACE).lower().replace("-", "_").replace(" ", "_")
        found = dictionary.get(key)
        if found is None and key.isdigit() and len(key) <= _MAX_ID_DIGITS:
            found = dictionary.by_id(int(key))
    if found is None:
        known = ", ".join(f"{p.name} ({p.id})" for p in dictionary.values())
        shown = repr(pattern)
        if len(shown) > _MAX_SHOWN:
            shown = shown[: _MAX_SHOWN - 1] + "…"
        raise EncodeError(f"unknown pattern {shown}: known patterns are {known}")
    return found
