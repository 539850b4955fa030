"""The vehicle side's split stays exact: ``pytest --vehicle-side`` (what ``make test-vehicle``
runs on Python 3.10 and 3.12) leaves out exactly the test modules that need the console's
packages, and the vehicle's own distribution (``vehicle/pyproject.toml``) holds exactly the
vehicle's packages. See tests/vehicle_side.py."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.test_layers import LAYER_OF
from tests.vehicle_side import (
    CONSOLE_PACKAGES,
    CONSOLE_SIDE,
    NOT_TYPE_CHECKED_AT_310,
    ROOT,
    TESTS,
    VEHICLE_PACKAGES,
    VEHICLE_TEST_DIRS,
    is_vehicle_side,
    type_checked_files,
)

#: A console module run in a subprocess, named in a string: ``-m cli.main``.
_RUNS = re.compile(rf"-m\s+({'|'.join(CONSOLE_PACKAGES)})\b")


def _uses(path: Path, root: Path = ROOT) -> set[str]:
    """Top-level packages ``path`` imports (at any depth) or runs with ``-m``; a ``tests.*``
    module it imports counts with what that module uses, in turn."""
    seen: set[Path] = set()
    found: set[str] = set()
    todo = [path]
    while todo:
        module = todo.pop()
        if module in seen:
            continue
        seen.add(module)
        for node in ast.walk(ast.parse(module.read_text(encoding="utf-8"))):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                names = [node.module]
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                found.update(_RUNS.findall(node.value))
            for name in names:
                found.add(name.split(".")[0])
                if name.startswith("tests."):
                    target = root.joinpath(*name.split("."))
                    todo += [target.with_suffix(".py"), target / "__init__.py"]
        todo = [p for p in todo if p.is_file()]
    return found


def test_the_console_side_list_is_exact() -> None:
    """A module of the vehicle's test folders is left out of the vehicle run if and only if it
    (or a test helper it imports) uses a package a vehicle does not install."""
    uses_console = {}
    for folder in VEHICLE_TEST_DIRS:
        for path in sorted((TESTS / folder).rglob("*.py")):
            console = sorted(_uses(path) & set(CONSOLE_PACKAGES))
            if console:
                uses_console[path.relative_to(ROOT).as_posix()] = console
    assert set(uses_console) == set(CONSOLE_SIDE), (
        "list in tests/vehicle_side.py CONSOLE_SIDE exactly the modules that use the console's "
        f"packages (or make them not): {uses_console}"
    )


def test_the_reader_sees_imports_helpers_and_subprocess_runs(tmp_path: Path) -> None:
    """Guards the test above: a lazy import, one through a test helper, a ``-m`` run."""
    (tmp_path / "tests" / "codec").mkdir(parents=True)
    (tmp_path / "tests" / "codec" / "helpers.py").write_text("import codec\nimport sim.model\n")
    test = tmp_path / "tests" / "codec" / "test_x.py"
    test.write_text("from tests.codec.helpers import x\n")
    assert {"tests", "codec", "sim"} <= _uses(test, tmp_path)
    test.write_text("def f():\n    from backend import app\n")
    assert "backend" in _uses(test, tmp_path)
    test.write_text("ARGS = ['python', '-m cli.main', 'patterns']\n")
    assert _uses(test, tmp_path) == {"cli"}


def test_the_console_packages_are_the_layers_above_the_vehicle() -> None:
    assert set(VEHICLE_PACKAGES) | set(CONSOLE_PACKAGES) == set(LAYER_OF)
    assert max(LAYER_OF[p] for p in VEHICLE_PACKAGES) < min(LAYER_OF[p] for p in CONSOLE_PACKAGES)


def test_the_vehicle_distribution_is_the_vehicle_side_on_3_10() -> None:
    vehicle = tomllib.loads((ROOT / "vehicle" / "pyproject.toml").read_text(encoding="utf-8"))
    console = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert vehicle["project"]["requires-python"] == ">=3.10"
    assert vehicle["project"]["dependencies"] == []  # the standard library only, on the vehicle
    setuptools = vehicle["tool"]["setuptools"]
    assert setuptools["packages"] == list(VEHICLE_PACKAGES)
    assert setuptools["package-dir"] == {p: f"../{p}" for p in VEHICLE_PACKAGES}
    # the console's own distribution keeps them too (same folders), and needs 3.11
    included = console["tool"]["setuptools"]["packages"]["find"]["include"]
    assert set(VEHICLE_PACKAGES) <= set(included)
    assert console["project"]["requires-python"] == ">=3.11"


@pytest.mark.parametrize(
    ("path", "collected"),
    [
        ("tests", True),
        ("tests/codec", True),
        ("tests/codec/test_bch.py", True),
        ("tests/nemesys_vehicle/test_core.py", True),
        ("tests/codec/test_protocol_doc.py", False),
        ("tests/onboard/test_guidance.py", False),
        ("tests/backend", False),
        ("tests/test_layers.py", False),
        ("codec", False),
    ],
)
def test_what_the_vehicle_run_collects(path: str, collected: bool) -> None:
    assert is_vehicle_side(ROOT / path) is collected


@pytest.mark.slow
def test_pytest_vehicle_side_collects_that() -> None:
    """The option through pytest itself (tests/conftest.py): the console-side modules of a
    vehicle folder and every other folder are not even imported."""
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "--vehicle-side", "--collect-only", "-q",
         "-p", "no:cacheprovider", "tests/onboard", "tests/vehicle_contract", "tests/sim"],
        cwd=ROOT, check=True, capture_output=True, text=True,
    ).stdout  # fmt: skip
    modules = {line.split("::")[0] for line in out.splitlines() if "::" in line}
    assert modules == {
        "tests/onboard/test_agent.py",
        "tests/onboard/test_agent_address.py",
        "tests/onboard/test_imports.py",
        "tests/vehicle_contract/test_address.py",
        "tests/vehicle_contract/test_fleet.py",
        "tests/vehicle_contract/test_names.py",
    }


def test_the_310_type_check_covers_the_vehicle_side() -> None:
    files = set(type_checked_files())
    assert {"codec/compat.py", "onboard/agent.py", "vehicle_contract/codes.py"} <= files
    assert "ros2/nemesys_vehicle/nemesys_vehicle/core.py" in files
    assert "tests/nemesys_vehicle/test_core.py" in files
    assert not files & (set(CONSOLE_SIDE) | set(NOT_TYPE_CHECKED_AT_310))
    assert not any(f.split("/")[0] in CONSOLE_PACKAGES for f in files)
