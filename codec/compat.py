"""What the vehicle side needs of Python 3.11's :mod:`enum`, without loading it.

The packages a vehicle installs (``codec``, ``planner``, ``vehicle_contract``, ``onboard`` and
the reference node ``ros2/nemesys_vehicle``) run on Python 3.10 and later; the console needs
3.11. Their enumerations (:class:`codec.RejectReason`, :class:`vehicle_contract.codes.Mode`) are
3.11's :class:`enum.StrEnum` as far as they use it: a member is a ``str`` (so ``==``, hashing
and ``json.dumps`` give its value), ``str()`` and ``format()`` give the value on every
version (a plain ``str, Enum`` on 3.10 gives ``"Mode.IDLE"``: acknowledgement and status
texts, f-strings and log lines would change), ``repr`` is the enum's, the class iterates its
members in order and has their number as ``len``, ``Cls(value)`` looks a member up
(``ValueError`` if none), ``Cls[name]`` by name, members are never copied (``copy``,
``deepcopy`` and pickle give the member itself) and cannot be reassigned. Nothing more of
:class:`enum.Enum` (``__members__``, ``in`` the class, ``reversed``): the vehicle side uses
none of it, and each method is resident memory. Members spell their values out (3.11's
``auto()`` is not reproduced).

:class:`StrEnum` is that, written out here rather than taken from :mod:`enum`, because the
onboard path's memory budget (1 MiB over a plain interpreter, ``nemesys bench onboard``)
cannot pay for :mod:`enum`: on 3.11 it loads :mod:`functools`, :mod:`collections`,
:mod:`operator` and more, about 0.8 MiB of resident memory before a frame is decoded. The type
checker sees :class:`enum.StrEnum` (what the members are for every purpose above); the one
difference at run time is that a member is not an :class:`enum.Enum` instance, so code that
dispatches on ``isinstance(x, Enum)`` (pydantic field types) should name the values
(``vehicle_contract.codes.REJECT_REASONS``, ``MODES``) instead. ``tests/codec/test_compat.py``
holds the two to the same behaviour.
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:
    import sys
    from collections.abc import Iterator

    if sys.version_info >= (3, 11):
        from enum import StrEnum
    else:  # the vehicle side's 3.10 type check: 3.11's class, as typeshed has it
        from enum import Enum

        class StrEnum(str, Enum):
            pass

else:  # not type-checked (the checker sees the above): annotations for the reader

    def _reserved(key: str, cls_name: str) -> bool:
        """The names :mod:`enum` keeps from being members: ``__dunder__``, ``_sunder_`` and
        private (name-mangled) ones."""
        return (key[:1] == "_" and key[-1:] == "_") or key.startswith(f"_{cls_name}__")

    class _StrEnumType(type):
        """The metaclass: a subclass's public ``str`` class attributes become its members."""

        def __new__(
            mcls, name: str, bases: tuple[type, ...], namespace: dict[str, object]
        ) -> _StrEnumType:
            cls = super().__new__(mcls, name, bases, namespace)
            members: dict[str, StrEnum] = {}
            for key, value in namespace.items():
                if not bases or type(value) is not str or _reserved(key, name):
                    continue
                member = str.__new__(cls, value)
                member._name_ = key
                member._value_ = value
                type.__setattr__(cls, key, member)
                members[key] = member
            type.__setattr__(cls, "_member_map_", members)
            type.__setattr__(cls, "_value2member_map_", {m._value_: m for m in members.values()})
            return cls

        def __call__(cls, value: object) -> StrEnum:
            if isinstance(value, cls):
                return value
            member = cls._value2member_map_.get(value) if type(value) is str else None
            if member is None:
                raise ValueError(f"{value!r} is not a valid {cls.__qualname__}")
            return member

        def __getitem__(cls, name: str) -> StrEnum:
            return cls._member_map_[name]

        def __iter__(cls) -> Iterator[StrEnum]:
            return iter(cls._member_map_.values())

        def __len__(cls) -> int:
            return len(cls._member_map_)

        def __setattr__(cls, name: str, value: object) -> None:
            if name in cls.__dict__.get("_member_map_", ()):
                raise AttributeError(f"cannot reassign member {name!r}")
            super().__setattr__(name, value)

        def __repr__(cls) -> str:
            return f"<enum {cls.__name__!r}>"

    class StrEnum(str, metaclass=_StrEnumType):
        """:class:`enum.StrEnum` of Python 3.11, as far as the vehicle side uses it."""

        @property
        def name(self) -> str:
            return self._name_

        @property
        def value(self) -> str:
            return self._value_

        def __str__(self) -> str:
            return self._value_

        def __format__(self, spec: str) -> str:
            return format(self._value_, spec)

        def __repr__(self) -> str:
            return f"<{type(self).__name__}.{self._name_}: {self._value_!r}>"

        def __reduce_ex__(self, protocol: object) -> tuple[type, tuple[str]]:
            return type(self), (self._value_,)

        def __copy__(self) -> StrEnum:
            return self

        def __deepcopy__(self, memo: object) -> StrEnum:
            return self


__all__ = ["StrEnum"]
