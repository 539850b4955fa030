"""Immutable value records for the onboard path, without :mod:`dataclasses`.

The vehicle imports :mod:`codec` and :mod:`planner` and must stay within a tight memory budget
(``nemesys bench planner`` measures it). ``import dataclasses`` pulls in :mod:`inspect`,
:mod:`ast`, :mod:`dis` and :mod:`tokenize`, about 1.2 MB of resident memory before a single
frame is decoded, so the onboard types derive from this small base instead. A record declares
its fields in ``__slots__`` (with annotations for the type checker), sets them once in
``__init__`` through :func:`init`, and gets value equality, hashing, a readable ``repr`` and
immutability from the slots.

The fields are the public names in ``__slots__`` along the MRO, in the order of the class's
annotations (``__slots__`` itself is kept sorted): that order shows in ``repr`` and
:meth:`Record.as_dict`. Private slots (``_cache``) hold derived state and are no part of
equality, hashing or ``repr``. Pickling and :mod:`copy` restore every slot without calling
``__init__``, as they do for a frozen dataclass.
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable

_FIELDS: dict[type, tuple[str, ...]] = {}
_SLOTS: dict[type, tuple[str, ...]] = {}

#: Sets an attribute on a record during ``__init__`` (records refuse ``setattr`` otherwise).
init = object.__setattr__


def slot_setters(cls: type, *names: str) -> tuple[Callable[[object, object], None], ...]:
    """The setters of ``cls``'s slots ``names``, for filling a record made with
    ``object.__new__(cls)`` on a hot path: about twice as fast as :func:`init`, and like it
    they bypass the record's refusal of ``setattr`` (use them only on a new record)."""
    setters = []
    for name in names:
        slot = next((k.__dict__[name] for k in cls.__mro__ if name in k.__dict__), None)
        if slot is None or not hasattr(slot, "__set__") or name not in _slots(cls):
            raise AttributeError(f"{cls.__name__} has no slot {name!r}")
        setters.append(slot.__set__)
    return tuple(setters)


def _own_slots(klass: type) -> tuple[str, ...]:
    """The attribute names of the slots ``klass`` itself declares (private names mangled)."""
    slots = klass.__dict__.get("__slots__", ())
    names = (slots,) if isinstance(slots, str) else tuple(slots)
    prefix = "_" + klass.__name__.lstrip("_")
    return tuple(
        prefix + n if n.startswith("__") and not n.endswith("__") else n
        for n in names
        if n not in ("__dict__", "__weakref__")
    )


def _fields(cls: type) -> tuple[str, ...]:
    names = _FIELDS.get(cls)
    if names is None:
        found: list[str] = []
        for klass in reversed(cls.__mro__):
            slots = _own_slots(klass)
            # Not inspect.get_annotations: importing inspect costs what this module saves.
            annotated = klass.__dict__.get("__annotations__", {})  # noqa: RUF063
            found.extend(n for n in annotated if n in slots)
            found.extend(n for n in slots if n not in annotated)
        names = _FIELDS[cls] = tuple(n for n in found if not n.startswith("_"))
    return names


def _slots(cls: type) -> tuple[str, ...]:
    names = _SLOTS.get(cls)
    if names is None:
        names = _SLOTS[cls] = tuple(n for k in reversed(cls.__mro__) for n in _own_slots(k))
    return names


def _restore(cls: type[Record], state: tuple[tuple[str, object], ...]) -> Record:
    """Unpickle (and copy) a record: its slots as they were, without ``__init__``."""
    record = object.__new__(cls)
    for name, value in state:
        init(record, name, value)
    return record


class Record:
    """Base class: fields are the public names in ``__slots__`` along the MRO."""

    __slots__ = ()

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable: cannot set {name!r}")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable: cannot delete {name!r}")

    def _values(self) -> tuple[object, ...]:
        return tuple(getattr(self, n) for n in _fields(type(self)))

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        assert isinstance(other, Record)
        return self._values() == other._values()

    def __hash__(self) -> int:
        return hash((type(self), self._values()))

    def __repr__(self) -> str:
        args = ", ".join(f"{n}={getattr(self, n)!r}" for n in _fields(type(self)))
        return f"{type(self).__name__}({args})"

    def __reduce__(self) -> tuple[object, ...]:
        cls = type(self)
        state = tuple((n, getattr(self, n)) for n in _slots(cls) if hasattr(self, n))
        return _restore, (cls, state)

    def as_dict(self) -> dict[str, object]:
        """Field name -> value (shallow)."""
        return {n: getattr(self, n) for n in _fields(type(self))}
