"""The cell file's `routines:` section as the routines node uses it, with what the manual section offers (the groups
and tools a routine may use must be the driver's). The BFF validates the file against the JSON Schema at start;
here only a directory that would leave DATA_DIR is fatal, other mismatches are dropped with a warning."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional

DEFAULT_DIRECTORY = "routines"


class ConfigError(ValueError):
    """The section cannot be used (names the field)."""


@dataclass(frozen=True)
class RoutinesConfig:
    directory: str                                   # relative to DATA_DIR
    groups: dict[str, int]                           # offered motion group -> its number of joints
    tools: dict[str, tuple[str, ...]]                # offered tool -> its action names (manual.tools)
    tool_groups: dict[str, str] = field(default_factory=dict)  # offered tool -> its motion group (manual.tools)
    speed: float = 0.0                               # m/s for pose steps; 0: the driver's default
    acceleration: float = 0.0                        # m/s^2; 0: the driver's default
    warnings: tuple[str, ...] = field(default=())    # what was dropped from the section, and why

    def group_names(self) -> str:
        return ", ".join(self.groups) or "none"

    def tool_names(self, group: str = "") -> str:
        """The offered tools (of `group` when given)."""
        return ", ".join(t for t in self.tools if not group or self.tool_groups.get(t) == group) or "none"


def _names(raw: Any) -> list[str]:
    return [x for x in raw if isinstance(x, str)] if isinstance(raw, list) else []


def _speed(section: Mapping[str, Any], key: str) -> float:
    value = section.get(key, 0)
    if value is None:
        return 0.0
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise ConfigError(f"routines.{key}: expected a number of at least 0, got {value!r}")
    return float(value)


def check_directory(directory: Any) -> str:
    """A relative path that stays inside DATA_DIR (the schema's relPath; checked again: it decides where we write)."""
    if not isinstance(directory, str) or not directory:
        raise ConfigError(f"routines.directory: expected a relative path, got {directory!r}")
    norm = os.path.normpath(directory)
    if os.path.isabs(directory) or norm == ".." or norm.startswith(".." + os.sep) or "\0" in directory:
        raise ConfigError(f"routines.directory: {directory!r} must be a path inside DATA_DIR")
    return norm


def parse_routines(cell: Mapping[str, Any]) -> RoutinesConfig:
    """Read `routines:` against `manual:`. Absent `groups`: every motion group; absent `tools`: none (the BFF's
    view gives the page the same). A tool belongs to its manual.tools[].group (default the first group); a
    routine uses the tools of its own group only."""
    section: Mapping[str, Any] = cell.get("routines") or {}
    manual: Mapping[str, Any] = cell.get("manual") or {}
    warnings: list[str] = []

    manual_groups: dict[str, int] = {}
    for g in manual.get("groups") or []:
        if isinstance(g, dict) and isinstance(g.get("name"), str):
            manual_groups[g["name"]] = len(g.get("joints") or [])
    manual_tools: dict[str, tuple[str, ...]] = {}
    manual_tool_groups: dict[str, str] = {}
    first_group = next(iter(manual_groups), "")
    for t in manual.get("tools") or []:
        if isinstance(t, dict) and isinstance(t.get("name"), str):
            manual_tools[t["name"]] = tuple(a["name"] for a in t.get("actions") or []
                                            if isinstance(a, dict) and isinstance(a.get("name"), str))
            manual_tool_groups[t["name"]] = t["group"] if isinstance(t.get("group"), str) else first_group

    groups: dict[str, int] = {}
    wanted = _names(section["groups"]) if "groups" in section else list(manual_groups)
    for i, name in enumerate(wanted):
        if name in manual_groups:
            groups[name] = manual_groups[name]
        else:
            warnings.append(f"routines.groups[{i}]: {name!r} is not a motion group of the robot driver "
                            f"(manual.groups: {', '.join(manual_groups) or 'none'}); ignored")
    tools: dict[str, tuple[str, ...]] = {}
    tool_groups: dict[str, str] = {}
    for i, name in enumerate(_names(section.get("tools"))):
        if name not in manual_tools:
            warnings.append(f"routines.tools[{i}]: {name!r} is not a tool of the robot driver "
                            f"(manual.tools: {', '.join(manual_tools) or 'none'}); ignored")
        elif manual_tool_groups[name] not in groups:
            # A routine uses the tools of its own group: this one could never be recorded or run.
            warnings.append(f"routines.tools[{i}]: tool {name!r} is on group {manual_tool_groups[name]!r} "
                            f"(manual.tools), which routines.groups does not offer ({', '.join(groups) or 'none'}); "
                            f"ignored")
        else:
            tools[name] = manual_tools[name]
            tool_groups[name] = manual_tool_groups[name]
    directory = check_directory(section.get("directory", DEFAULT_DIRECTORY))
    return RoutinesConfig(directory, groups, tools, tool_groups, _speed(section, "speed"),
                          _speed(section, "acceleration"), tuple(warnings))


def routines_dir(config: RoutinesConfig, data_dir: Optional[str] = None) -> str:
    """$DATA_DIR/<routines.directory>, absolute; DATA_DIR defaults to `.data` in the working directory."""
    base = data_dir if data_dir is not None else (os.environ.get("DATA_DIR") or ".data")
    return os.path.join(os.path.abspath(base), config.directory)
