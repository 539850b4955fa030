"""JSON Schema building blocks of the vehicle contract (:mod:`vehicle_contract.contract`): the
dictionary's commands and the planner's vehicle state as schemas, and validation errors as
one line each that names the field."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from codec import describe_dictionary

if TYPE_CHECKING:
    from jsonschema.exceptions import ValidationError
    from jsonschema.protocols import Validator


def param_schema(field: dict[str, Any]) -> dict[str, Any]:
    """One parameter of the dictionary: a number within its range, or one of its choices."""
    unit = f" ({field['unit']})" if field["unit"] else ""
    if field["kind"] == "choice":
        return {"enum": list(field["choices"]), "description": field["label"]}
    return {
        "type": "number",
        "minimum": field["min"],
        "maximum": field["max"],
        "description": f"{field['label']}{unit}",
    }


def command_schema() -> dict[str, Any]:
    """A command as :func:`onboard.agent.command_json` makes it, from the dictionary: the
    pattern's name and ID, and exactly its parameters (values as the vehicle uses them)."""
    patterns = describe_dictionary()
    by_pattern = [
        {
            "if": {"properties": {"pattern": {"const": p["name"]}}, "required": ["pattern"]},
            "then": {
                "properties": {
                    "pattern_id": {"const": p["id"]},
                    "params": {
                        "type": "object",
                        "required": [f["name"] for f in p["fields"]],
                        "properties": {f["name"]: param_schema(f) for f in p["fields"]},
                        "additionalProperties": False,
                    },
                }
            },
        }
        for p in patterns
    ]
    return {
        "type": "object",
        "description": "a command of the dictionary (docs/patterns.md): name, ID, parameters "
        "in SI units as the vehicle uses them (after snapping to the frame's codes)",
        "required": ["pattern", "pattern_id", "params"],
        "properties": {
            "pattern": {"enum": [p["name"] for p in patterns]},
            "pattern_id": {"type": "integer", "minimum": 0, "maximum": 15},
            "params": {"type": "object"},
        },
        "allOf": by_pattern,
    }


def vehicle_state_schema() -> dict[str, Any]:
    """The state a plan was made from (``planner.VehicleState.as_dict``): the console replays
    the plan from it, so every number is a finite number and nothing else is allowed."""
    number = {"type": "number"}
    return {
        "type": "object",
        "description": "the vehicle as its navigation saw it when it planned (NED m, deg, m/s, "
        "ROS time s); the console replans from it to draw the very path the vehicle flies",
        "required": ["x_m", "y_m", "z_m", "heading_deg", "speed_mps", "t_s", "segment"],
        "properties": {
            "x_m": number,
            "y_m": number,
            "z_m": {"type": "number", "minimum": 0},
            "heading_deg": number,
            "speed_mps": number,
            "t_s": number,
            "segment": {"type": ["integer", "null"], "minimum": 0},
        },
        "additionalProperties": False,
    }


def _where(error: ValidationError) -> str:
    return ".".join(str(p) for p in error.absolute_path)


def _leaves(error: ValidationError) -> list[tuple[str, str]]:
    """(field, message) of what is wrong: for a failed ``anyOf`` (a command or null), every
    error of the alternative of the instance's type."""
    if not error.context:
        return [(_where(error), error.message)]
    branches: dict[object, list[ValidationError]] = {}
    for child in error.context:
        if child.parent is error:
            branches.setdefault(child.relative_schema_path[0], []).append(child)

    def wrong_type(errors: list[ValidationError]) -> bool:
        return any(e.validator == "type" and not e.path for e in errors)

    fits = [errors for errors in branches.values() if not wrong_type(errors)]
    if not fits:
        types = [repr(e.validator_value) for es in branches.values() for e in es]
        return [(_where(error), f"{error.instance!r} is not of type {' or '.join(types)}")]
    return [leaf for child in fits[0] for leaf in _leaves(child)]


def problems(validator: Validator, obj: Any) -> list[str]:
    """What is wrong with ``obj`` under ``validator``'s schema: one line per error, each
    naming the field (``a.b: ...``, or the message naming a missing field); empty when valid."""
    out: list[str] = []
    errors = sorted(validator.iter_errors(obj), key=lambda e: str(list(e.path)))
    for where, message in (leaf for error in errors for leaf in _leaves(error)):
        line = f"{where}: {message}" if where else message
        if line not in out:  # a command is checked by its own schema and by the outcome's
            out.append(line)
    return out
