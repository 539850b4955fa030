"""``codec.compat.StrEnum`` behaves as Python 3.11's :class:`enum.StrEnum` wherever the vehicle
side writes a member: ``str()``, ``format()`` and f-strings, ``%``, JSON, comparison and lookup
by value. The same tests run on 3.10 (``make test-vehicle``: the ``str, Enum`` stand-in) and on
3.11 and later (the standard class)."""

from __future__ import annotations

import enum
import json
import sys

import pytest

from codec import RejectReason
from codec.compat import StrEnum


class Colour(StrEnum):
    RED = "red"
    DARK_BLUE = "dark blue"


def test_is_the_standard_class_where_there_is_one() -> None:
    if sys.version_info >= (3, 11):
        assert StrEnum is enum.StrEnum
    else:
        assert StrEnum.__mro__[1:3] == (str, enum.Enum)


@pytest.mark.parametrize("member", [Colour.RED, Colour.DARK_BLUE, RejectReason.NO_SYNC])
def test_a_member_reads_as_its_value(member: StrEnum) -> None:
    value = member.value
    assert str(member) == value and type(str(member)) is str
    assert format(member) == value
    assert f"{member}" == value
    assert f"{member:>12}" == value.rjust(12)
    assert f"[{member!s}]" == f"[{value}]"
    assert "%s" % member == value  # noqa: UP031  (the %-format the logging module uses)
    assert json.dumps(member) == json.dumps(value)
    assert json.dumps({member: [member]}) == json.dumps({value: [value]})
    assert member == value and hash(member) == hash(value)
    assert type(member)(value) is member
    assert isinstance(member, str)


def test_repr_and_name_stay_the_enums() -> None:
    assert repr(Colour.RED) == "<Colour.RED: 'red'>"
    assert Colour.DARK_BLUE.name == "DARK_BLUE"
    assert [c.value for c in Colour] == ["red", "dark blue"]


def test_an_unknown_value_is_refused() -> None:
    with pytest.raises(ValueError, match="'green' is not a valid Colour"):
        Colour("green")


def test_the_codecs_reasons_read_as_their_codes() -> None:
    """What an acknowledgement and a log line write: the code, never ``RejectReason.X``."""
    assert f"rejected: {RejectReason.CRC_MISMATCH}" == "rejected: crc_mismatch"
    assert json.dumps({"reason": RejectReason.NO_SYNC}) == '{"reason": "no_sync"}'
