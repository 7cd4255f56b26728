"""A wait_topic step's condition on one message: a field path (`data`, `pose.position.z`, `status[0].level`) and
equals / above / below. Works on ROS messages (attributes) and on plain dicts (tests)."""
from __future__ import annotations

import math
import re
from typing import Any

_PART = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


class ConditionError(ValueError):
    """The message has no such field, or its value cannot be compared that way."""


def field_value(msg: Any, path: str) -> Any:
    value = msg
    for part in path.split("."):
        m = _PART.match(part)
        if not m:
            raise ConditionError(f"bad field path {path!r}")
        name, indices = m.group(1), m.group(2)
        if isinstance(value, dict):
            if name not in value:
                raise ConditionError(f"the message has no field {path!r}")
            value = value[name]
        else:
            slots = getattr(value, "__slots__", None)
            if (slots is not None and name not in slots) or not hasattr(value, name):
                raise ConditionError(f"the message has no field {path!r}")
            value = getattr(value, name)
        for idx in re.findall(r"\[(\d+)\]", indices):
            try:
                value = value[int(idx)]
            except (IndexError, TypeError, KeyError):
                raise ConditionError(f"{path!r}: no element {idx}") from None
    return value


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def holds(value: Any, condition: str, expected: Any) -> bool:
    """Whether `value` (from the message) satisfies the condition. Raises ConditionError on a type mismatch."""
    if condition == "equals":
        if isinstance(expected, bool):
            if isinstance(value, bool) or value in (0, 1):
                return bool(value) == expected
            raise ConditionError(f"value {value!r} is not true/false")
        if _is_number(expected):
            if not _is_number(value):
                raise ConditionError(f"value {value!r} is not a number")
            return math.isclose(float(value), float(expected), rel_tol=1e-9, abs_tol=1e-9)
        return str(value) == str(expected)
    if condition in ("above", "below"):
        if not _is_number(value) and not isinstance(value, bool):
            raise ConditionError(f"value {value!r} is not a number ({condition} needs one)")
        return float(value) > float(expected) if condition == "above" else float(value) < float(expected)
    raise ConditionError(f"unknown condition {condition!r}")


def describe_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    text = repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= 60 else text[:57] + "..."
