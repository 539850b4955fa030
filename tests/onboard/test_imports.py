"""The onboard agent takes its reason codes and modes from the vehicle contract, and only from
its light module: the onboard process loads none of the contract's topics, schemas or
validators (``jsonschema``), nor anything heavy (the vehicle's memory budget:
``bench/_reconfig_memory.py``)."""

from __future__ import annotations

import subprocess
import sys

from tests.codec.test_imports import HEAVY, plain_modules_after

#: The agent and guidance, as the onboard process imports them (``bench/_reconfig_memory.py``).
ONBOARD = "from onboard.agent import OnboardAgent; from onboard.guidance import Guidance"
#: The contract's modules the vehicle does not run: the console, vehicle-check and the
#: simulator read them.
CONTRACT_ONLY = (
    "vehicle_contract.contract",
    "vehicle_contract.payloads",
    "vehicle_contract.schema",
    "jsonschema",
)


def _modules_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print('\\n'.join(sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    )
    return set(result.stdout.split())


def test_the_agent_loads_the_contracts_codes_and_nothing_else_of_it() -> None:
    bare = _modules_after("pass")
    loaded = _modules_after(ONBOARD)
    assert "vehicle_contract.codes" in loaded
    for name in CONTRACT_ONLY:
        assert name not in loaded, f"{name} is loaded by the onboard agent"
    for name in HEAVY:
        assert name not in loaded or name in bare, f"{name} is loaded by the onboard agent"


def test_the_probe_sees_the_contract_when_it_is_imported() -> None:
    """Guards the test above against passing because the probe itself is broken."""
    loaded = _modules_after(ONBOARD + "; import vehicle_contract.contract")
    assert {"vehicle_contract.contract", "vehicle_contract.payloads"} <= loaded


#: All the standard library the onboard process loads beyond a plain interpreter's own: the
#: planner's trigonometry, and ``from __future__ import annotations`` (an import at run time).
ONBOARD_STDLIB = {"math", "__future__"}


def test_the_agent_loads_no_standard_library_module_but_math() -> None:
    """In a plain interpreter (no site), the onboard process's baseline: enum, collections,
    functools, typing, importlib and the like cost the vehicle's memory budget more than the
    agent's own code (``nemesys bench onboard``)."""
    bare = plain_modules_after("pass")
    loaded = plain_modules_after(ONBOARD + "; import planner; planner.validate")
    ours = ("codec", "planner", "onboard", "vehicle_contract")
    added = {m for m in loaded - bare if m.partition(".")[0] not in ours}
    assert added == ONBOARD_STDLIB
    assert "enum" in plain_modules_after("import enum") - bare  # the probe sees a loaded module
