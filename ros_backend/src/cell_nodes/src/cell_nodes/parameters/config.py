"""The cell file's `parameters:` section as the node and the reader use it. The BFF validates it against the JSON
Schema at start; this module also checks what a schema cannot (unique ids, min <= max, a default that its own rules
accept) and raises ConfigError naming the field."""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Optional

from ..texts import english
from .values import TYPES, DEFAULT_MAX_LENGTH, InvalidValue, ParamDef, canonical

_ID = re.compile(r"[a-z][a-z0-9_-]*")
MAX_DECIMALS = 15           # more is below a float64's precision
MAX_STRING_LENGTH = 10000   # a parameter, not a document


class ConfigError(ValueError):
    """The parameters section cannot be used (names the field: `parameters.items[2].default: ...`)."""


@dataclass(frozen=True)
class ParametersConfig:
    csv: str                       # relative to DATA_DIR, from the cell file only
    items: tuple[ParamDef, ...]

    def by_id(self) -> dict[str, ParamDef]:
        return {d.id: d for d in self.items}


def default_data_dir() -> str:
    """$DATA_DIR, else `.data` at the repository root (as the BFF and `npm start` do)."""
    env = os.environ.get("DATA_DIR")
    if env:
        return os.path.abspath(env)
    return str(Path(__file__).resolve().parents[6] / ".data")


def csv_path(config: ParametersConfig, data_dir: Optional[str] = None) -> str:
    return os.path.join(data_dir or default_data_dir(), config.csv)


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{where}: expected a number, got {value!r}")
    return value


def _text(item: Mapping[str, Any], key: str, where: str, required: bool) -> str:
    """A label or category may be one per language: the node names the parameter by the English."""
    value = english(item.get(key))
    if isinstance(item.get(key), dict):
        where, key = f"{where}.{key}", "en"
    if value is None and not required:
        return ""
    if not isinstance(value, str) or (required and not value.strip()):
        raise ConfigError(f"{where}.{key}: expected {'a non-empty' if required else 'a'} string, got {value!r}")
    return value


def _relative_path(value: Any) -> str:
    if not isinstance(value, str) or not value or "\0" in value:
        raise ConfigError(f"parameters.csv: expected a file path relative to DATA_DIR, got {value!r}")
    parts = value.replace("\\", "/").split("/")
    if value.startswith("/") or ".." in parts or parts[-1] in ("", "."):
        raise ConfigError(f"parameters.csv: must be a file path inside DATA_DIR (relative, no `..`), got {value!r}")
    return value


def _default_text(defn_type: str, value: Any, where: str) -> str:
    """The cell file's default as the text the CSV would hold (YAML gave a typed value)."""
    if value is None:
        raise ConfigError(f"{where}: missing (every parameter needs a default)")
    if defn_type == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where}: expected a whole number, got {value!r}")
        return str(value)
    if defn_type == "float":
        _number(value, where)
        return repr(float(value)) if isinstance(value, float) else str(value)  # repr: 0.1 stays 0.1
    if defn_type == "bool":
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: expected true or false, got {value!r}")
        return "true" if value else "false"
    if not isinstance(value, str):
        raise ConfigError(f"{where}: expected a string, got {value!r}")
    return value


def _item(item: Any, where: str) -> ParamDef:
    if not isinstance(item, Mapping):
        raise ConfigError(f"{where}: expected a mapping, got {item!r}")
    pid = item.get("id")
    if not isinstance(pid, str) or not _ID.fullmatch(pid):
        raise ConfigError(f"{where}.id: expected lower-case letters, digits, _ or - (starting with a letter), "
                          f"got {pid!r}")
    ptype = item.get("type")
    if ptype not in TYPES:
        raise ConfigError(f"{where}.type: expected one of {', '.join(TYPES)}, got {ptype!r}")
    kw: dict[str, Any] = {"id": pid, "type": ptype, "label": _text(item, "label", where, True),
                          "category": _text(item, "category", where, False), "unit": _text(item, "unit", where, False)}
    for key in ("min", "max"):
        if item.get(key) is not None:
            if ptype not in ("int", "float"):
                raise ConfigError(f"{where}.{key}: only int and float parameters have limits")
            kw[key] = _number(item[key], f"{where}.{key}")
    if kw.get("min") is not None and kw.get("max") is not None and kw["min"] > kw["max"]:
        raise ConfigError(f"{where}.min: {kw['min']} is above max {kw['max']}")
    if item.get("options") is not None or ptype == "enum":
        if ptype != "enum":
            raise ConfigError(f"{where}.options: only enum parameters have options")
        options = item.get("options")
        if not isinstance(options, list) or not options:
            raise ConfigError(f"{where}.options: an enum needs a non-empty list of options, got {options!r}")
        for i, opt in enumerate(options):
            if not isinstance(opt, str) or not opt.strip() or opt != opt.strip():
                raise ConfigError(f"{where}.options[{i}]: expected a non-empty string without surrounding blanks "
                                  f"(quote numbers: \"1\"), got {opt!r}")
        if len(set(options)) != len(options):
            raise ConfigError(f"{where}.options: listed twice: "
                              f"{', '.join(sorted({o for o in options if options.count(o) > 1}))}")
        kw["options"] = tuple(options)
    if item.get("decimals") is not None:
        decimals = item["decimals"]
        if ptype != "float":
            raise ConfigError(f"{where}.decimals: only float parameters have decimals")
        if isinstance(decimals, bool) or not isinstance(decimals, int) or not 0 <= decimals <= MAX_DECIMALS:
            raise ConfigError(f"{where}.decimals: expected a whole number from 0 to {MAX_DECIMALS}, got {decimals!r}")
        kw["decimals"] = decimals
    if ptype == "string":
        bound = item.get("max_length", DEFAULT_MAX_LENGTH)
        if isinstance(bound, bool) or not isinstance(bound, int) or not 1 <= bound <= MAX_STRING_LENGTH:
            raise ConfigError(f"{where}.max_length: expected a whole number from 1 to {MAX_STRING_LENGTH}, "
                              f"got {bound!r}")
        kw["max_length"] = bound
    elif item.get("max_length") is not None:
        raise ConfigError(f"{where}.max_length: only string parameters have a length bound")
    text = _default_text(ptype, item.get("default"), f"{where}.default")
    probe = ParamDef(default=text, **kw)
    try:  # the default must pass its own rules (range, decimals, options, length)
        text = canonical(probe, text)[0]
    except InvalidValue as e:
        raise ConfigError(f"{where}.default: {e}") from None
    return ParamDef(default=text, **kw)


def parse_parameters(cell: Mapping[str, Any]) -> Optional[ParametersConfig]:
    """The whole cell file in; None when it has no `parameters:` section."""
    section = cell.get("parameters")
    if section is None:
        return None
    if not isinstance(section, Mapping):
        raise ConfigError(f"parameters: expected a mapping, got {section!r}")
    csv = _relative_path(section.get("csv"))
    items = section.get("items")
    if items is None:
        items = []
    if not isinstance(items, list):
        raise ConfigError(f"parameters.items: expected a list, got {items!r}")
    defs: list[ParamDef] = []
    seen: dict[str, int] = {}
    for i, item in enumerate(items):
        defn = _item(item, f"parameters.items[{i}]")
        if defn.id in seen:
            raise ConfigError(f"parameters.items[{i}].id: {defn.id!r} is already the id of items[{seen[defn.id]}]")
        seen[defn.id] = i
        defs.append(defn)
    return ParametersConfig(csv=csv, items=tuple(defs))
