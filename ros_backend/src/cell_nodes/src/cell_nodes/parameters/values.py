"""One parameter's definition and the rules for its values, as text in and text out.

Values travel as text everywhere (the CSV, the services, the topic): `canonical(defn, text)` checks a text against
the definition and returns the text to store and the typed value, or raises InvalidValue with a message that names
the parameter by its label, for the operator.
"""
from __future__ import annotations

import math
import re
import unicodedata
from dataclasses import dataclass
from decimal import Decimal
from typing import Optional, Union

Value = Union[int, float, bool, str]

TYPES = ("int", "float", "bool", "string", "enum")
DEFAULT_MAX_LENGTH = 200          # a string parameter's bound when the cell file gives none
MAX_NUMBER_TEXT = 40              # longer number texts are refused before parsing
MAX_SAFE_INT = 2 ** 53 - 1        # the page is JavaScript: larger ints would not survive a round trip there
SHOWN_CHARS = 40                  # how much of a bad value a message quotes

# ASCII digits only: `int()` and `float()` also take other scripts' digits and underscores ("1_000").
_INT = re.compile(r"[+-]?[0-9]+")
_FLOAT = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_TEXT_CONTROLS_ALLOWED = "\n\t"   # multi-line text and tabs are fine; other control characters are not


class InvalidValue(ValueError):
    """A value text a parameter does not accept; str() is the operator's message, naming the parameter."""


@dataclass(frozen=True)
class ParamDef:
    """One entry of the cell file's `parameters.items`, checked (config.parse_parameters builds these)."""
    id: str
    category: str
    label: str
    type: str                          # one of TYPES
    default: str                       # canonical text
    unit: str = ""
    min: Optional[float] = None        # int and float only
    max: Optional[float] = None
    options: tuple[str, ...] = ()      # enum only
    decimals: Optional[int] = None     # float only: at most this many digits after the point
    max_length: int = 0                # string only (DEFAULT_MAX_LENGTH unless the cell file says)


def format_limit(x: float) -> str:
    """A limit from the cell file as people write it: 200, not 200.0; 0.5 stays 0.5."""
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    return repr(x) if isinstance(x, float) else str(x)


def _with_unit(text: str, unit: str) -> str:
    return f"{text} {unit}" if unit else text


def shown(text: str) -> str:
    """A bad value quoted for a message: control characters visible, long ones cut."""
    cut = text[:SHOWN_CHARS]
    return repr(cut) + ("…" if len(text) > SHOWN_CHARS else "")


def show_value(defn: ParamDef, text: str) -> str:
    """A stored value for a message: numbers with their unit, text quoted."""
    if defn.type in ("string", "enum"):
        return shown(text)
    return _with_unit(text, defn.unit) if defn.type in ("int", "float") else text


def _decimal_places(text: str) -> int:
    exponent = Decimal(text).normalize().as_tuple().exponent
    return max(0, -int(exponent))


def _check_range(defn: ParamDef, number: float, text: str) -> None:
    if defn.min is not None and number < defn.min:
        raise InvalidValue(f"{defn.label}: {_with_unit(text, defn.unit)} is below the minimum "
                           f"{_with_unit(format_limit(defn.min), defn.unit)}")
    if defn.max is not None and number > defn.max:
        raise InvalidValue(f"{defn.label}: {_with_unit(text, defn.unit)} is above the maximum "
                           f"{_with_unit(format_limit(defn.max), defn.unit)}")


def canonical(defn: ParamDef, text: str) -> tuple[str, Value]:
    """The text to store and the typed value, or InvalidValue. Ints are normalised (`+07` -> `7`); floats are kept
    as written (stripped, no leading `+`), so `0.1` and `1e-05` stay exactly that; bools are `true`/`false` in any
    case; enum values must be one of the options; strings are kept exactly as given."""
    if not isinstance(text, str):
        raise InvalidValue(f"{defn.label}: expected text, got {type(text).__name__}")
    label = defn.label
    if defn.type in ("int", "float", "bool", "enum"):
        stripped = text.strip()   # spreadsheets pad cells; surrounding blanks never mean anything for these types
        if not stripped:
            raise InvalidValue(f"{label}: a value is needed")
    if defn.type == "int":
        if len(stripped) > MAX_NUMBER_TEXT or not _INT.fullmatch(stripped):
            raise InvalidValue(f"{label}: {shown(stripped)} is not a whole number")
        number = int(stripped)
        if abs(number) > MAX_SAFE_INT:
            raise InvalidValue(f"{label}: {stripped} is too large (at most {MAX_SAFE_INT} either way)")
        out = str(number)
        _check_range(defn, number, out)
        return out, number
    if defn.type == "float":
        if len(stripped) > MAX_NUMBER_TEXT or not _FLOAT.fullmatch(stripped):
            raise InvalidValue(f"{label}: {shown(stripped)} is not a number")
        out = stripped[1:] if stripped.startswith("+") else stripped
        number = float(out)
        if not math.isfinite(number):
            raise InvalidValue(f"{label}: {out} is too large")
        _check_range(defn, number, out)
        if defn.decimals is not None and _decimal_places(out) > defn.decimals:
            if defn.decimals == 0:
                raise InvalidValue(f"{label}: {out} must have no decimals")
            raise InvalidValue(f"{label}: {out} has more than {defn.decimals} "
                               f"decimal{'s' if defn.decimals != 1 else ''}")
        return out, number
    if defn.type == "bool":
        low = stripped.lower()
        if low not in ("true", "false"):
            raise InvalidValue(f"{label}: {shown(stripped)} is not true or false")
        return low, low == "true"
    if defn.type == "enum":
        if stripped not in defn.options:
            raise InvalidValue(f"{label}: {shown(stripped)} is not one of {', '.join(defn.options)}")
        return stripped, stripped
    if defn.type == "string":
        bound = defn.max_length or DEFAULT_MAX_LENGTH
        if len(text) > bound:
            raise InvalidValue(f"{label}: {len(text)} characters, at most {bound}")
        for ch in text:
            category = unicodedata.category(ch)
            if (category == "Cc" and ch not in _TEXT_CONTROLS_ALLOWED) or category == "Cs":
                raise InvalidValue(f"{label}: contains a control character (U+{ord(ch):04X})")
        return text, text
    raise InvalidValue(f"{label}: unknown type {defn.type!r}")


def typed(defn: ParamDef, text: str) -> Value:
    """The typed value of a text that `canonical` accepted."""
    return canonical(defn, text)[1]
