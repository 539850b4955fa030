"""``codec.compat.StrEnum`` behaves as Python 3.11's :class:`enum.StrEnum` wherever the vehicle
side uses a member: ``str()``, ``format()`` and f-strings, ``%``, JSON, comparison, lookup by
value and name, iteration, copies and pickles. The same tests run on 3.10 (``make
test-vehicle``) and on 3.11 and later, where the standard class is the reference; and the
onboard path never loads :mod:`enum` (its memory budget)."""

from __future__ import annotations

import copy
import enum
import json
import pickle
import sys
from typing import Any

import pytest

from codec import RejectReason
from codec.compat import StrEnum
from tests.codec.test_imports import plain_modules_after


class Colour(StrEnum):
    RED = "red"
    DARK_BLUE = "dark blue"


def test_the_onboard_path_loads_no_enum() -> None:
    loaded = plain_modules_after("from codec.compat import StrEnum; import codec")
    assert "codec.compat" in loaded and "enum" not in loaded
    assert "enum" in plain_modules_after("import enum")  # the probe sees it when loaded


@pytest.mark.skipif(sys.version_info < (3, 11), reason="enum.StrEnum is 3.11's")
def test_behaves_as_the_standard_class() -> None:
    factory: Any = vars(enum)["StrEnum"]  # 3.11's, unknown to the 3.10 type check
    standard = factory("Colour", {"RED": "red", "DARK_BLUE": "dark blue"})
    for ours, theirs in ((Colour, standard), (Colour.RED, standard.RED)):
        assert repr(ours) == repr(theirs) and str(ours) == str(theirs)
    for member, reference in zip(Colour, standard, strict=True):
        assert (member.name, member.value) == (reference.name, reference.value)
        assert (str(member), format(member, ">12"), f"{member!s}", "%s" % member) == (  # noqa: UP031
            str(reference), format(reference, ">12"), f"{reference!s}", "%s" % reference,  # noqa: UP031
        )  # fmt: skip
        assert json.dumps([member]) == json.dumps([reference])
        assert type(member.value) is type(reference.value) is str
    assert len(Colour) == len(standard) == 2
    assert Colour["DARK_BLUE"] is Colour.DARK_BLUE and Colour(Colour.RED) is Colour.RED
    with pytest.raises(ValueError, match=str(standard.__name__)):
        standard("green")


def test_members_are_never_copied_nor_reassigned() -> None:
    for member in (Colour.DARK_BLUE, RejectReason.CRC_MISMATCH):
        assert copy.copy(member) is member and copy.deepcopy([member])[0] is member
        assert pickle.loads(pickle.dumps(member)) is member
    with pytest.raises(AttributeError):
        Colour.RED = "green"  # type: ignore[misc]
    assert Colour.RED.value == "red"


def test_methods_and_reserved_names_are_no_members() -> None:
    class Shade(StrEnum):
        LIGHT = "light"
        _ignore_ = "x"  # a _sunder_ name, as enum reserves them

        def darker(self) -> str:
            return f"dark {self}"

    assert list(Shade) == [Shade.LIGHT] and Shade.LIGHT.darker() == "dark light"
