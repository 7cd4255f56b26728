"""One parameter's definition and the rules for its values, as text in and text out.

Values travel as text everywhere (the CSV, the services, the topic): `canonical(defn, text)` checks a text against
the definition and returns the text to store and the typed value, or raises InvalidValue with a message that names
the parameter by its (English) label, for the operator, said with a code (`said.say`) so the app can say it in the
user's language.
"""
from __future__ import annotations

import math
import re
import unicodedata
from dataclasses import dataclass
from decimal import Decimal
from typing import Optional, Union

from ..said import Said, say

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
    """A value text a parameter does not accept; str() is the operator's message, naming the parameter; `said` the
    same with its code."""

    def __init__(self, said: Said) -> None:
        super().__init__(said)
        self.said = said


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
    """A number with its unit ("250 mm"; a number alone without one), said so the app writes the number its way."""
    return say("parameters.quantity", "{number} {unit}", number=text, unit=unit) if unit else text


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
        raise InvalidValue(say("parameters.below_min", "{label}: {value} is below the minimum {min}", label=defn.label,
                               value=_with_unit(text, defn.unit), min=_with_unit(format_limit(defn.min), defn.unit)))
    if defn.max is not None and number > defn.max:
        raise InvalidValue(say("parameters.above_max", "{label}: {value} is above the maximum {max}", label=defn.label,
                               value=_with_unit(text, defn.unit), max=_with_unit(format_limit(defn.max), defn.unit)))


def canonical(defn: ParamDef, text: str) -> tuple[str, Value]:
    """The text to store and the typed value, or InvalidValue. Ints are normalised (`+07` -> `7`); floats are kept
    as written (stripped, no leading `+`), so `0.1` and `1e-05` stay exactly that; bools are `true`/`false` in any
    case; enum values must be one of the options; strings are kept exactly as given."""
    if not isinstance(text, str):
        raise InvalidValue(say("parameters.not_text", "{label}: expected text, got {kind}", label=defn.label,
                               kind=type(text).__name__))
    label = defn.label
    if defn.type in ("int", "float", "bool", "enum"):
        stripped = text.strip()   # spreadsheets pad cells; surrounding blanks never mean anything for these types
        if not stripped:
            raise InvalidValue(say("parameters.value_needed", "{label}: a value is needed", label=label))
    if defn.type == "int":
        if len(stripped) > MAX_NUMBER_TEXT or not _INT.fullmatch(stripped):
            raise InvalidValue(say("parameters.not_whole", "{label}: {value} is not a whole number", label=label,
                                   value=shown(stripped)))
        number = int(stripped)
        if abs(number) > MAX_SAFE_INT:
            raise InvalidValue(say("parameters.too_large_int", "{label}: {value} is too large (at most {max} either way)",
                                   label=label, value=stripped, max=MAX_SAFE_INT))
        out = str(number)
        _check_range(defn, number, out)
        return out, number
    if defn.type == "float":
        if len(stripped) > MAX_NUMBER_TEXT or not _FLOAT.fullmatch(stripped):
            raise InvalidValue(say("parameters.not_number", "{label}: {value} is not a number", label=label,
                                   value=shown(stripped)))
        out = stripped[1:] if stripped.startswith("+") else stripped
        number = float(out)
        if not math.isfinite(number):
            raise InvalidValue(say("parameters.too_large", "{label}: {value} is too large", label=label, value=out))
        _check_range(defn, number, out)
        if defn.decimals is not None and _decimal_places(out) > defn.decimals:
            if defn.decimals == 0:
                raise InvalidValue(say("parameters.no_decimals", "{label}: {value} must have no decimals", label=label,
                                       value=out))
            if defn.decimals == 1:
                raise InvalidValue(say("parameters.too_many_decimals_one", "{label}: {value} has more than {count} decimal",
                                       label=label, value=out, count=1))
            raise InvalidValue(say("parameters.too_many_decimals", "{label}: {value} has more than {count} decimals",
                                   label=label, value=out, count=defn.decimals))
        return out, number
    if defn.type == "bool":
        low = stripped.lower()
        if low not in ("true", "false"):
            raise InvalidValue(say("parameters.not_bool", "{label}: {value} is not true or false", label=label,
                                   value=shown(stripped)))
        return low, low == "true"
    if defn.type == "enum":
        if stripped not in defn.options:
            raise InvalidValue(say("parameters.not_option", "{label}: {value} is not one of {options}", label=label,
                                   value=shown(stripped), options=", ".join(defn.options)))
        return stripped, stripped
    if defn.type == "string":
        bound = defn.max_length or DEFAULT_MAX_LENGTH
        if len(text) > bound:
            raise InvalidValue(say("parameters.too_long", "{label}: {length} characters, at most {max}", label=label,
                                   length=len(text), max=bound))
        for ch in text:
            category = unicodedata.category(ch)
            if (category == "Cc" and ch not in _TEXT_CONTROLS_ALLOWED) or category == "Cs":
                raise InvalidValue(say("parameters.control_char", "{label}: contains a control character (U+{char})",
                                       label=label, char=f"{ord(ch):04X}"))
        return text, text
    raise InvalidValue(say("parameters.unknown_type", "{label}: unknown type {type}", label=label, type=repr(defn.type)))


def typed(defn: ParamDef, text: str) -> Value:
    """The typed value of a text that `canonical` accepted."""
    return canonical(defn, text)[1]
