#!/usr/bin/env python3
"""Build our ROS interfaces for ROS 2 Jazzy with rosidl (CMake), into a prefix beside the ROS 2 venv.

Run by scripts/bootstrap.sh (stage ros2) with the ROS 2 venv's python. Two kinds of package:
- ours (cell_msgs): built from the same .msg/.srv/.action files as for ROS 1 (ros_backend/src/<pkg>), adapted in
  the build tree where the two syntaxes differ (time, duration, Header). One source of truth.
- public ones (control_msgs, rosapi_msgs): their public Jazzy definitions, kept verbatim in ros2/interfaces/<pkg>
  (ROS 2's FollowJointTrajectory is not ROS 1's), so their type hashes are the public ones.

Usage: build_interfaces.py --venv V --prefix P --build B
"""
from __future__ import annotations

import argparse
import os
import pathlib
import re
import shutil
import subprocess
import sys
from typing import Dict, List, Set, Tuple

HERE = pathlib.Path(__file__).resolve().parent
ROS1_SRC = HERE.parent / "src"

# (package, source folder, adapt from ROS 1 syntax); in build order.
PACKAGES: List[Tuple[str, pathlib.Path, bool]] = [
    ("control_msgs", HERE / "interfaces" / "control_msgs", False),
    ("rosapi_msgs", HERE / "interfaces" / "rosapi_msgs", False),
    ("cell_msgs", ROS1_SRC / "cell_msgs", True),
]
KINDS = ("msg", "srv", "action")
ROS1_TO_ROS2_TYPES = {"time": "builtin_interfaces/Time", "duration": "builtin_interfaces/Duration",
                      "Header": "std_msgs/Header"}
# ROS 1 packages that have no ROS 2 counterpart to depend on (actions are built in on ROS 2).
ROS1_ONLY_DEPENDENCIES = {"actionlib_msgs"}
_FIELD = re.compile(r"^(\s*)([A-Za-z_][\w/]*)((?:\[[^\]]*\])?)(\s+.*)$")


def adapt_line(line: str) -> str:
    """One line of a ROS 1 definition in ROS 2 syntax (comments, constants and separators unchanged)."""
    m = _FIELD.match(line)
    if not m or line.lstrip().startswith("#"):
        return line
    indent, base, array, rest = m.groups()
    return f"{indent}{ROS1_TO_ROS2_TYPES.get(base, base)}{array}{rest}"


def adapt(text: str) -> str:
    return "\n".join(adapt_line(line) for line in text.split("\n"))


def dependencies(files: List[pathlib.Path], own: str) -> Set[str]:
    """Packages named by `pkg/Type` field types in the definitions."""
    deps: Set[str] = set()
    for path in files:
        for line in path.read_text().splitlines():
            m = _FIELD.match(line)
            if m and not line.lstrip().startswith("#") and "/" in m.group(2):
                deps.add(m.group(2).split("/")[0])
    if any(p.suffix == ".action" for p in files):
        deps.add("action_msgs")
    return deps - {own} - ROS1_ONLY_DEPENDENCIES


def write_package(name: str, src: pathlib.Path, adapt_syntax: bool, out: pathlib.Path) -> List[str]:
    """The package's ROS 2 source tree under `out`; returns its interface files (relative)."""
    if out.exists():
        shutil.rmtree(out)
    files: List[pathlib.Path] = []
    rel: List[str] = []
    for kind in KINDS:
        for path in sorted((src / kind).glob(f"*.{kind}")):
            target = out / kind / path.name
            target.parent.mkdir(parents=True, exist_ok=True)
            text = path.read_text()
            target.write_text(adapt(text) if adapt_syntax else text)
            files.append(target)
            rel.append(f"{kind}/{path.name}")
    deps = sorted(dependencies(files, name))
    find = "\n".join(f"find_package({d} REQUIRED)" for d in deps)
    (out / "CMakeLists.txt").write_text(f"""cmake_minimum_required(VERSION 3.10)
project({name})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
{find}
rosidl_generate_interfaces(${{PROJECT_NAME}}
  {' '.join(rel)}
  DEPENDENCIES {' '.join(deps)})
ament_export_dependencies(rosidl_default_runtime)
ament_package()
""")
    depends = "\n".join(f"  <depend>{d}</depend>" for d in deps)
    (out / "package.xml").write_text(f"""<?xml version="1.0"?>
<package format="3">
  <name>{name}</name>
  <version>0.1.0</version>
  <description>{name} for ROS 2, built by ros_backend/ros2/build_interfaces.py</description>
  <maintainer email="cell@example.com">cell</maintainer>
  <license>Apache-2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
{depends}
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
""")
    return rel


def fix_wheel_cmake_paths(venv: pathlib.Path) -> int:
    """The wheels' exported CMake targets name their build machine's include paths, which CMake refuses
    ("includes non-existent path"): point them at this venv's Python headers and numpy. Returns files changed."""
    import sysconfig

    import numpy
    py_include = sysconfig.get_paths()["include"]
    np_include = numpy.get_include()
    patterns = [(re.compile(r"/opt/python/cp\d+-cp\d+/include/python3\.\d+"), py_include),
                (re.compile(r"/[^;\"]*?/site-packages/numpy/(?:_core|core)/include"), np_include)]
    changed = 0
    for path in (venv / "share").glob("*/cmake/*.cmake"):
        text = path.read_text()
        new = text
        for pattern, real in patterns:
            new = pattern.sub(real, new)
        if new != text:
            path.write_text(new)
            changed += 1
    return changed


def build(name: str, src: pathlib.Path, build_dir: pathlib.Path, prefix: pathlib.Path, venv: pathlib.Path,
          env: Dict[str, str]) -> None:
    build_dir.mkdir(parents=True, exist_ok=True)
    log = build_dir / "build.log"
    with open(log, "w") as out:
        for cmd in (["cmake", str(src), f"-DCMAKE_INSTALL_PREFIX={prefix}",
                     f"-DPython3_EXECUTABLE={venv / 'bin' / 'python'}", "-DBUILD_TESTING=OFF",
                     "-DCMAKE_BUILD_TYPE=Release"],
                    ["make", f"-j{os.cpu_count() or 2}"], ["make", "install"]):
            if subprocess.call(cmd, cwd=build_dir, env=env, stdout=out, stderr=subprocess.STDOUT) != 0:
                sys.stderr.write(log.read_text()[-6000:])
                raise SystemExit(f"building {name} for ROS 2 failed at `{' '.join(cmd[:2])}` (log: {log})")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--venv", required=True, type=pathlib.Path)
    ap.add_argument("--prefix", required=True, type=pathlib.Path)
    ap.add_argument("--build", required=True, type=pathlib.Path)
    args = ap.parse_args()
    venv, prefix, build_root = args.venv.resolve(), args.prefix.resolve(), args.build.resolve()
    fix_wheel_cmake_paths(venv)
    if prefix.exists():
        shutil.rmtree(prefix)
    env = dict(os.environ)
    env["PATH"] = f"{venv / 'bin'}:{env.get('PATH', '')}"
    env["AMENT_PREFIX_PATH"] = f"{prefix}:{venv}"
    env["CMAKE_PREFIX_PATH"] = f"{prefix}:{venv}"
    env["PYTHONPATH"] = str(prefix / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages")
    env["LD_LIBRARY_PATH"] = f"{prefix / 'lib'}:{venv / 'lib'}"
    for name, src, adapt_syntax in PACKAGES:
        tree = build_root / "src" / name
        write_package(name, src, adapt_syntax, tree)
        build(name, tree, build_root / "build" / name, prefix, venv, env)
        print(f"[ros2 interfaces] {name} built", flush=True)


if __name__ == "__main__":
    main()
