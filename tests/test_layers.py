"""The house's direction: a top-level package imports only packages of a lower layer.

    codec <- planner <- vehicle_contract <- onboard      the vehicle side (what a vehicle installs)
      <- rosbridge <- station, sim                        the links, the simulator
      <- backend <- bench <- analysis <- cli              the console, measurements, the CLI

The vehicle contract sits under the onboard agent: the contract owns the reason codes and the
modes, the agent imports them (``vehicle_contract.codes``). ``station`` and ``sim`` share a
layer and import neither each other. Imports are read with ``ast`` from every module, so an
import inside a function (a lazy one) or under ``TYPE_CHECKING`` counts as much as one at the
top. The reference ROS 2 node's own rule (vehicle side only) is tests/nemesys_vehicle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: The layers, lowest first; a package may import any package of a lower layer only.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("codec",),
    ("planner",),
    ("vehicle_contract",),
    ("onboard",),
    ("rosbridge",),
    ("station", "sim"),
    ("backend",),
    ("bench",),
    ("analysis",),
    ("cli",),
)
LAYER_OF = {package: n for n, layer in enumerate(LAYERS) for package in layer}


def imported_packages(source: str) -> list[tuple[str, int]]:
    """(top-level package, line) of every absolute import in ``source``, at any depth."""
    found: list[tuple[str, int]] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [(alias.name.split(".")[0], node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.append((node.module.split(".")[0], node.lineno))
    return found


def violations(package: str, root: Path = ROOT) -> list[str]:
    """Every import in ``package`` of a package of its own or a higher layer."""
    layer = LAYER_OF[package]
    out = []
    for path in sorted((root / package).rglob("*.py")):
        for other, line in imported_packages(path.read_text(encoding="utf-8")):
            if other != package and other in LAYER_OF and LAYER_OF[other] >= layer:
                out.append(f"{path.relative_to(root)}:{line} imports {other}")
    return out


@pytest.mark.parametrize("package", list(LAYER_OF))
def test_a_package_imports_only_lower_layers(package: str) -> None:
    assert (ROOT / package / "__init__.py").is_file(), f"{package} is not a package here"
    assert violations(package) == []


def test_every_top_level_package_has_a_layer() -> None:
    """A new package is placed in the house, not left out of this test."""
    packages = {p.parent.name for p in ROOT.glob("*/__init__.py")}
    assert packages - {"tests"} == set(LAYER_OF)


def test_lazy_and_type_checking_imports_count(tmp_path: Path) -> None:
    """Guards the test above: the reader sees an import at any depth, and the rule names it."""
    source = (
        "from typing import TYPE_CHECKING\n"
        "import codec\n"
        "if TYPE_CHECKING:\n"
        "    from sim.simulation import Simulation\n"
        "def later() -> None:\n"
        "    import backend.console\n"
        "    from . import sibling\n"
    )
    assert imported_packages(source) == [("typing", 1), ("codec", 2), ("sim", 4), ("backend", 6)]
    (tmp_path / "station").mkdir()
    (tmp_path / "station" / "x.py").write_text(source, encoding="utf-8")
    assert violations("station", tmp_path) == [
        "station/x.py:4 imports sim",
        "station/x.py:6 imports backend",
    ]
