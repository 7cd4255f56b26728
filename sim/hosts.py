"""Which address each motion group's UR controller has: the rule the robot driver (cell_nodes.manual.config
.resolve_hosts) and scripts/stack.js (bff/src/core/config/hosts.js resolveHosts) follow too.

  1. UR_HOSTS (`<group>=<host>[,<group>=<host>...]`) names the group: that host (several stacks side by side);
  2. else the group's `host` in the cell file (manual.groups[].host);
  3. else UR_HOST, else 127.0.0.1.
"""
from __future__ import annotations

from typing import Any, Mapping

DEFAULT_HOST = "127.0.0.1"


def parse_host_list(text: str, name: str = "UR_HOSTS") -> dict[str, str]:
    """`g=h,g2=h2` -> {g: h, g2: h2}; blank entries are skipped, any other entry without `=` is an error."""
    out: dict[str, str] = {}
    for entry in (e.strip() for e in (text or "").split(",")):
        group, _, host = entry.partition("=")
        if entry and not (group.strip() and host.strip()):
            raise ValueError(f'{name}: "{entry}" is not <group>=<host>')
        if entry:
            out[group.strip()] = host.strip()
    return out


def resolve_hosts(section: Any, environ: Mapping[str, str]) -> dict[str, str]:
    """The controller address of every group of the manual section, in its order."""
    overrides = parse_host_list(environ.get("UR_HOSTS", ""))
    fallback = (environ.get("UR_HOST") or "").strip() or DEFAULT_HOST
    groups = section.get("groups") if isinstance(section, Mapping) else None
    out: dict[str, str] = {}
    for g in groups if isinstance(groups, list) else []:
        if isinstance(g, Mapping) and isinstance(g.get("name"), str) and g["name"]:
            own = g.get("host").strip() if isinstance(g.get("host"), str) else ""
            out[g["name"]] = overrides.get(g["name"]) or own or fallback
    return out
