"""What the vehicle side needs of Python 3.11 on the Python 3.10 of ROS 2 Humble (Ubuntu 22.04).

The packages a vehicle installs (``codec``, ``planner``, ``vehicle_contract``, ``onboard`` and
the reference node ``ros2/nemesys_vehicle``) run on Python 3.10 and later; the console needs
3.11. :class:`StrEnum` is the one 3.11 name they use: on 3.11 and later it *is*
:class:`enum.StrEnum`; on 3.10 it is a ``str, Enum`` whose ``str()`` and ``format()`` give the
value, as 3.11's do (a plain ``str, Enum`` gives ``"Mode.IDLE"`` for both: acknowledgement and
status texts, f-strings and log lines would change). ``json.dumps`` writes the value either
way (a member is a ``str``). Members spell their values out: 3.11's ``auto()`` (the lowercased
name) is not reproduced.

The lowest layer holds it so every vehicle package above imports it from one place. It loads
nothing but :mod:`enum` and :mod:`sys`, both already loaded by ``codec`` (the onboard path's
memory budget: ``tests/codec/test_imports.py``). Ruff checks this file at ``py310``
(``per-file-target-version`` in ``pyproject.toml``): at the project's ``py311`` it would
rewrite the 3.10 branch away. ``make lint`` runs mypy a second time on the vehicle side at
``--python-version 3.10``, where the 3.10 branch is the one it checks.
"""

from __future__ import annotations

import sys

if sys.version_info >= (3, 11):
    from enum import StrEnum
else:
    from enum import Enum

    class StrEnum(str, Enum):
        """:class:`enum.StrEnum` of Python 3.11, as far as the vehicle side uses it."""

        def __str__(self) -> str:
            # Enum.__format__ (3.10) formats str(self) when a class overrides __str__
            return str(self._value_)


__all__ = ["StrEnum"]
