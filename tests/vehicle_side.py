"""Which tests are the vehicle side's: what ``pytest --vehicle-side`` collects.

A vehicle installs ``codec``, ``planner``, ``vehicle_contract`` and ``onboard``
(``vehicle/pyproject.toml``) and runs the reference node (``ros2/nemesys_vehicle``), on the
Python of its ROS 2: 3.10 on Humble (Ubuntu 22.04), 3.12 on Jazzy (Ubuntu 24.04). The console
needs 3.11. ``make test-vehicle`` runs these tests in venvs of 3.10 and 3.12 that hold the
vehicle side and the tests' own tools, nothing of the console (``scripts/test_vehicle.sh``).

The vehicle side's tests are the test folders of those packages, less the modules that drive
them through the console's packages (:data:`CONSOLE_SIDE`, with the reason): those run in the
project's own suite only. ``tests/test_vehicle_side.py`` reads every module's imports so this
list stays exact.

``python -m tests.vehicle_side`` prints the vehicle side's Python files (its packages, the
node, these tests) for ``make lint``'s second mypy run, at Python 3.10.
"""

from __future__ import annotations

from pathlib import Path

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent

#: What a vehicle installs (vehicle/pyproject.toml), and the reference node's package.
VEHICLE_PACKAGES = ("codec", "planner", "vehicle_contract", "onboard")
NODE_PACKAGE = "ros2/nemesys_vehicle/nemesys_vehicle"

#: The test folders of the vehicle's packages and of the reference node.
VEHICLE_TEST_DIRS = (*VEHICLE_PACKAGES, "nemesys_vehicle")

#: Top-level packages of this repository a vehicle does not install (docs/architecture.md).
CONSOLE_PACKAGES = ("rosbridge", "station", "sim", "backend", "bench", "analysis", "cli")

#: Modules of those folders left out of the vehicle run, and why.
CONSOLE_SIDE: dict[str, str] = {
    "tests/codec/test_protocol_doc.py": (
        "docs/protocol.md's console sessions run the `nemesys` command line (cli)"
    ),
    "tests/vehicle_contract/test_contract.py": (
        "the contract as the console, the simulator and vehicle-check read it (backend, sim, "
        "station, rosbridge, cli)"
    ),
    "tests/vehicle_contract/test_messages.py": (
        "the pose and status messages through rosbridge's JSON conversions (rosbridge)"
    ),
    "tests/onboard/test_guidance.py": "guidance flown by the simulator's vehicle model (sim)",
}


def is_vehicle_side(path: Path) -> bool:
    """Whether ``path`` (a folder or a file under tests/) is collected by ``--vehicle-side``.

    tests/ itself and the vehicle's folders are; their modules are unless listed in
    :data:`CONSOLE_SIDE`; every other folder and the modules directly in tests/ are not.
    """
    try:
        parts = path.resolve().relative_to(TESTS).parts
    except ValueError:
        return False
    if not parts:
        return True
    if parts[0] not in VEHICLE_TEST_DIRS:
        return False
    return "/".join(("tests", *parts)) not in CONSOLE_SIDE


#: Left out of the 3.10 type check, and why.
NOT_TYPE_CHECKED_AT_310: dict[str, str] = {
    "codec/batch.py": (
        "the console's Monte Carlo path (numpy): the console venv's numpy (2.3 and later need "
        "3.11) types its operators Any at 3.10; its tests run on 3.10's numpy in test-vehicle"
    ),
    "tests/codec/test_batch.py": "codec/batch.py's tests (above)",
    "codec/batch_addressed.py": "the batch path of addressed frames (numpy, as codec/batch.py)",
    "tests/codec/test_batch_addressed.py": "codec/batch_addressed.py's tests (above)",
}


#: The modules directly in tests/ that the vehicle run loads: the root conftest and its imports.
TESTS_ROOT_MODULES = ("__init__.py", "conftest.py", "tiers.py", "vehicle_side.py")


def type_checked_files() -> list[str]:
    """The vehicle side's Python files, from the repository's root: its packages, the node
    and the tests the vehicle run loads, less :data:`NOT_TYPE_CHECKED_AT_310`."""
    files = [f for p in (*VEHICLE_PACKAGES, NODE_PACKAGE) for f in (ROOT / p).rglob("*.py")]
    files += [TESTS / name for name in TESTS_ROOT_MODULES]
    files += [f for d in VEHICLE_TEST_DIRS for f in (TESTS / d).rglob("*.py") if is_vehicle_side(f)]
    names = {f.relative_to(ROOT).as_posix() for f in files}
    return sorted(names - set(NOT_TYPE_CHECKED_AT_310))


if __name__ == "__main__":
    print("\n".join(type_checked_files()))
