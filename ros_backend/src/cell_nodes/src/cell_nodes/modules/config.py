"""The cell file's `modules:` section as the modules node uses it (the BFF validates it against the JSON Schema at
start; this module raises only on what the node cannot work with, naming the field)."""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence

DEFAULT_TIMEOUT_S = 10.0
# A launch file reference: `<package>/<path inside the package>.launch`, never absolute, never `..`.
_REF = re.compile(r"^[A-Za-z][A-Za-z0-9_]*(/[A-Za-z0-9_.\-]+)+\.launch$")
_NODE = re.compile(r"^/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$")


class ConfigError(ValueError):
    """The modules section cannot be used (names the field: `modules[1].nodes[0]: ...`)."""


@dataclass(frozen=True)
class ModuleSpec:
    name: str
    launch: tuple[str, ...]            # launch file references from the cell file, in order
    nodes: tuple[str, ...]             # global node names (leading slash)
    roles: tuple[str, ...] = ()
    timeout_s: float = DEFAULT_TIMEOUT_S

    @property
    def launchable(self) -> bool:
        return bool(self.launch)


def global_name(node: str) -> str:
    return node if node.startswith("/") else "/" + node


def parse_modules(section: Optional[Sequence[Any]]) -> list[ModuleSpec]:
    if section is None:
        return []
    if not isinstance(section, list):
        raise ConfigError("modules: must be a list")
    out: list[ModuleSpec] = []
    seen: set[str] = set()
    for i, m in enumerate(section):
        where = f"modules[{i}]"
        if not isinstance(m, dict) or not isinstance(m.get("name"), str) or not m["name"].strip():
            raise ConfigError(f"{where}.name: a module needs a name")
        name = m["name"]
        if name in seen:
            raise ConfigError(f"{where}.name: duplicate module name {name!r}")
        seen.add(name)
        launch = tuple(m.get("launch") or ())
        for j, ref in enumerate(launch):
            if not isinstance(ref, str) or not _REF.match(ref) or ".." in ref.split("/"):
                raise ConfigError(f"{where}.launch[{j}]: {ref!r} is not a `package/path/file.launch` reference")
        nodes = []
        for j, n in enumerate(m.get("nodes") or ()):
            if not isinstance(n, str) or not _NODE.match(n):
                raise ConfigError(f"{where}.nodes[{j}]: {n!r} is not a ROS node name")
            if global_name(n) not in nodes:
                nodes.append(global_name(n))
        timeout = m.get("timeout_s", DEFAULT_TIMEOUT_S)
        if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not timeout > 0:
            raise ConfigError(f"{where}.timeout_s: must be a positive number of seconds")
        out.append(ModuleSpec(name=name, launch=launch, nodes=tuple(nodes), roles=tuple(m.get("roles") or ()),
                              timeout_s=float(timeout)))
    return out


def resolve_launch_file(ref: str, package_path: Callable[[str], str]) -> str:
    """`cell_bringup/launch/modules/vision.launch` -> the absolute path of that file inside the package.

    `package_path(pkg)` finds a package's directory (rospkg.RosPack().get_path). The result must be an existing
    file inside that directory (no `..`, no symlink out of it)."""
    if not _REF.match(ref) or ".." in ref.split("/"):
        raise ConfigError(f"{ref!r} is not a `package/path/file.launch` reference")
    package, rel = ref.split("/", 1)
    try:
        root = os.path.realpath(package_path(package))
    except Exception as e:  # rospkg.ResourceNotFound and friends
        raise ConfigError(f"{ref}: package {package!r} not found") from e
    path = os.path.realpath(os.path.join(root, rel))
    if os.path.commonpath([root, path]) != root:
        raise ConfigError(f"{ref}: outside the package {package!r}")
    if not os.path.isfile(path):
        raise ConfigError(f"{ref}: no such launch file in {package!r}")
    return path
