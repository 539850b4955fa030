"""The records that replace dataclasses on the onboard path (codec._record): construction,
immutability, value equality, hashing, repr, pickling and copying."""

from __future__ import annotations

import copy
import pickle

import pytest

from codec import (
    DICTIONARY,
    Accepted,
    ChoiceScale,
    Command,
    Decoded,
    DecodeError,
    Encoded,
    Field,
    Frame,
    NumericScale,
    Pattern,
    Rejected,
    RejectReason,
    Section,
    Segment,
    Snap,
    encode_frame,
)
from codec._record import Record, init

ENC = encode_frame("square", speed=0.5, depth=2, side_span=12.34, direction="cw")
CIRCLE = DICTIONARY["circle"]
RECORDS: list[Record] = [
    ENC,
    ENC.command,
    ENC.frame,
    ENC.snaps[2],
    Decoded(ENC.command, 2, 1),
    Accepted(100, Decoded(ENC.command, 0)),
    Rejected(7, DecodeError(RejectReason.NO_SYNC, "no sync")),
    Section("crc", 76, 4),
    Segment("0", "0.1", 50),
    CIRCLE,
    CIRCLE.fields[0],
    CIRCLE.fields[0].scale,
    CIRCLE.fields[3].scale,
]
IDS = [type(r).__name__ for r in RECORDS]


@pytest.mark.parametrize("record", RECORDS, ids=IDS)
def test_records_are_immutable(record: Record) -> None:
    name = next(iter(record.as_dict()))
    with pytest.raises(AttributeError, match="immutable"):
        setattr(record, name, None)
    with pytest.raises(AttributeError, match="immutable"):
        delattr(record, name)
    with pytest.raises(AttributeError):
        record.__dict__  # noqa: B018  slots only
    with pytest.raises(AttributeError, match="immutable"):
        record.extra = 1


# DecodeError (inside Rejected) does not pickle: its __init__ takes the reason first.
PICKLABLE = [r for r in RECORDS if not isinstance(r, Rejected)]


@pytest.mark.parametrize("record", PICKLABLE, ids=[type(r).__name__ for r in PICKLABLE])
def test_records_survive_pickle_and_copy(record: Record) -> None:
    for clone in (pickle.loads(pickle.dumps(record)), copy.copy(record), copy.deepcopy(record)):
        assert type(clone) is type(record)
        assert clone == record
        assert hash(clone) == hash(record)
        assert repr(clone) == repr(record)


@pytest.mark.parametrize("record", RECORDS, ids=IDS)
def test_records_rebuild_from_their_fields(record: Record) -> None:
    fields = record.as_dict()
    assert type(record)(*fields.values()) == record  # positional, in declaration order
    assert type(record)(**fields) == record  # keywords


def test_equality_is_by_value_and_class() -> None:
    assert Decoded(ENC.command, 2) == Decoded(ENC.command, corrected=2, sync_errors=0)
    assert Decoded(ENC.command, 2) != Decoded(ENC.command, 1)
    assert Section("a", 1, 2) != ("a", 1, 2)
    assert len({Frame(5), Frame(5), Frame(6)}) == 2
    # Like a dataclass with compare=False, the numeric table is no part of equality.
    a = NumericScale((Segment("0", "1", 3),), name="n")
    b = NumericScale((Segment("0", "1", 3),), name="n")
    a.values  # noqa: B018  builds a's table only
    assert a == b and hash(a) == hash(b)
    assert NumericScale((Segment("0", "1", 3),), name="m") != a


def test_repr_lists_fields_in_declaration_order() -> None:
    assert repr(Section("crc", 76, 4)) == "Section(name='crc', start=76, length=4)"
    assert repr(Decoded(ENC.command, 2, 1)) == (
        f"Decoded(command={ENC.command!r}, corrected=2, sync_errors=1)"
    )
    assert repr(Snap("laps", "", 3, 3)) == "Snap(field='laps', unit='', requested=3, sent=3)"
    assert repr(Segment("0", "0.1", 50)) == "Segment(start='0', step='0.1', count=50)"
    assert repr(ChoiceScale(("a", "b"), "x")) == "ChoiceScale(choices=('a', 'b'), name='x')"
    scale = repr(NumericScale((Segment("1", "1", 3),), first_code=1, integer=True))
    assert scale == (
        "NumericScale(segments=(Segment(start='1', step='1', count=3),), name='', first_code=1, "
        "integer=True, period=None, rel_error_from=None)"
    )
    # Classes that had repr=False keep their own.
    assert repr(CIRCLE) == "<Pattern 3 circle>"
    assert repr(ENC.command).startswith("<Command square ")


def test_as_dict() -> None:
    field = CIRCLE.fields[0]
    assert Field(**field.as_dict()) == field  # type: ignore[arg-type]
    assert Command(**ENC.command.as_dict()) == ENC.command  # type: ignore[arg-type]
    assert Pattern(**CIRCLE.as_dict()) == CIRCLE  # type: ignore[arg-type]
    assert list(Encoded(ENC.command, (), ENC.frame).as_dict()) == ["command", "snaps", "frame"]


def test_a_subclass_adds_fields_after_its_base() -> None:
    class Point(Record):
        __slots__ = ("x", "y")
        y: int  # annotation order, not slot order, is the field order
        x: int

        def __init__(self, y: int, x: int) -> None:
            init(self, "y", y)
            init(self, "x", x)

    class Tagged(Point):
        __slots__ = ("_cache", "tag")
        tag: str
        _cache: int  # private: not a field

        def __init__(self, y: int, x: int, tag: str) -> None:
            super().__init__(y, x)
            init(self, "tag", tag)
            init(self, "_cache", 0)

    assert repr(Point(1, 2)) == "Point(y=1, x=2)"
    t = Tagged(1, 2, "a")
    assert repr(t) == "Tagged(y=1, x=2, tag='a')"
    assert t == Tagged(1, 2, "a") and t != Point(1, 2)
    assert t.as_dict() == {"y": 1, "x": 2, "tag": "a"}


def test_pickle_restores_private_state_without_init() -> None:
    scale = NumericScale((Segment("0", "0.5", 4),), name="x")
    assert pickle.loads(pickle.dumps(scale))._table is None
    scale.values  # noqa: B018  builds the table
    clone = copy.deepcopy(scale)
    assert clone._table == (0.0, 0.5, 1.0, 1.5) and clone == scale

    class Cached(Record):
        __slots__ = ("__secret", "__weakref__", "_derived", "value")
        value: int
        _derived: int

        def __init__(self, value: int) -> None:
            init(self, "value", value)
            init(self, "_derived", value * 2)
            init(self, "_Cached__secret", value * 3)

    c = Cached(5)
    restored = copy.copy(c)
    assert restored == c and restored._derived == 10
    assert getattr(restored, "_Cached__secret") == 15  # noqa: B009  mangled name
