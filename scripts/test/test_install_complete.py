"""Every system command and Debian-packaged Python module the project's own files use comes from the
bootstrap's package list (scripts/apt-packages.txt) or its Depends closure, so a fresh machine gets it.

The uses are read from the code, so a new one is checked without editing this test:
- commands: the first word of every command in shell scripts and in shell strings (`bash -c ...`, the
  supervisor's and tests' ROS command strings), the program of every spawn/execFile/subprocess call, and
  every literal /usr/bin/X or /bin/X path;
- Python modules: every top-level import in the project's Python files (node scripts included), resolved
  in the project's ROS environment.
A command or module that resolves to a file owned by a Debian package (`dpkg -S`) must be owned by a
package in the closure (`apt-cache depends --recurse --no-recommends ...`) or an Essential one.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# Given on the machine before the bootstrap runs (README: Debian 12 with Node 20), or made by it (the venv).
PREREQUISITES = {"node", "npm", "npx", "python", "python3", "pip", "pip3"}
SHELL_WORDS = {
    "if", "then", "else", "elif", "fi", "for", "in", "do", "done", "while", "until", "case", "esac", "function",
    "cd", "source", ".", "exec", "export", "local", "set", "unset", "shift", "return", "exit", "trap", "wait",
    "echo", "printf", "read", "eval", "true", "false", "test", "[", "[[", "declare", "mapfile", "builtin",
    "command", "type", "kill", "let", "break", "continue", "sudo", "env", "nice", "time", "timeout", "{", "}",
}


def project_files() -> list[Path]:
    out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.split()
    skip = ("package-lock.json", "app/static/", "node_modules/", "scripts/test/test_install_complete.py")
    return [ROOT / f for f in out if not any(s in f for s in skip) and (ROOT / f).is_file()]


def apt_list() -> list[str]:
    lines = (ROOT / "scripts" / "apt-packages.txt").read_text().splitlines()
    return [ln.split("#")[0].strip() for ln in lines if ln.split("#")[0].strip()]


@lru_cache(maxsize=1)
def closure() -> frozenset[str]:
    out = subprocess.run(["apt-cache", "depends", "--recurse", "--no-recommends", "--no-suggests", "--no-conflicts",
                          "--no-breaks", "--no-replaces", "--no-enhances", *apt_list()],
                         capture_output=True, text=True, check=True).stdout
    names = {ln.strip().strip("<>").split(":")[0] for ln in out.splitlines() if ln and not ln[0].isspace()}
    # Essential and required packages are on every Debian system.
    base = subprocess.run(["dpkg-query", "-W", "-f", "${Package} ${Essential} ${Priority}\n"], capture_output=True,
                          text=True, check=True).stdout
    names |= {ln.split()[0] for ln in base.splitlines() if ln.endswith((" yes required", " yes", " required"))}
    return frozenset(names)


def owner(path: str) -> str | None:
    """The Debian package owning a file (merged /usr: try /bin/x for /usr/bin/x too), None if none does."""
    candidates = [path, os.path.realpath(path)]
    for p in list(candidates):
        if p.startswith("/usr/"):
            candidates.append(p[4:])
    for p in candidates:
        r = subprocess.run(["dpkg", "-S", p], capture_output=True, text=True)
        if r.returncode == 0:
            return r.stdout.split(":")[0].split(",")[0].strip()
    return None


# --- commands -------------------------------------------------------------------------------------------

def shell_commands(text: str) -> set[str]:
    """First words of the commands in a piece of shell text."""
    words = set()
    defined = set(re.findall(r"^\s*(?:function\s+)?([A-Za-z_][\w-]*)\s*\(\)\s*\{", text, re.M))
    text = re.sub(r"'[^'\n]*'", "''", text)  # quoted arguments are not commands
    text = re.sub(r"\$\{[^}]*\}|\$\([^)]*\bsed\b[^)]*\)", " ", text)  # parameter expansions
    for line in text.splitlines():
        line = line.split(" #")[0] if not line.lstrip().startswith("#") else ""
        for part in re.split(r"&&|\|\||[;|(`]|\$\(|\bthen\b|\bdo\b|\belse\b", line):
            tokens = part.split()
            while tokens and (re.match(r"^\w+=", tokens[0]) or tokens[0] in {"sudo", "exec", "env", "nice", "time",
                                                                              "timeout", "!", "$SUDO", "command"}):
                tokens = tokens[1:]
                while tokens and tokens[0].startswith("-"):
                    tokens = tokens[1:]
            if tokens and re.match(r"^[A-Za-z_][\w.+-]*$", tokens[0]):
                words.add(tokens[0])
    return words - defined


STRING = re.compile(r"'((?:[^'\\\n]|\\.)*)'|\"((?:[^\"\\\n]|\\.)*)\"|`((?:[^`\\]|\\.)*)`", re.S)
# A program and its argument list: spawn('cmd', [...]), run('cmd', [...]), Popen(["cmd", ...]).
CALL = re.compile(r"\b(?:spawn|spawnSync|execFile|execFileSync|run|Popen|call|check_call|check_output)\("
                  r"\s*(?:\[\s*['\"]([A-Za-z_][\w.+-]*)['\"]|['\"]([A-Za-z_][\w.+-]*)['\"]\s*,\s*\[)")
ABS_PATH = re.compile(r"(?<![\w.~/-])(/(?:usr/)?s?bin/[A-Za-z_][\w.+-]*)")


def commands_used() -> tuple[dict[str, set[str]], set[str]]:
    """command (name or absolute path) -> files using it; and the commands certainly run (not guessed from a
    string), which must be installed."""
    uses: dict[str, set[str]] = {}
    certain: set[str] = set()

    def add(cmd: str, f: Path, sure: bool = False) -> None:
        uses.setdefault(cmd, set()).add(str(f.relative_to(ROOT)))
        if sure:
            certain.add(cmd)

    for f in project_files():
        try:
            text = f.read_text()
        except UnicodeDecodeError:
            continue
        first = text.split("\n", 1)[0]
        is_shell = f.suffix == ".sh" or f.name == "run" and "bash" in first or (first.startswith("#!") and "bash" in first)
        if f.suffix in {".md", ".json", ".yaml", ".yml", ".txt", ".svg", ".css", ".html"}:
            continue
        if is_shell:
            for w in shell_commands(text):
                add(w, f, True)
        else:
            for m in CALL.finditer(text):
                add(m.group(1) or m.group(2), f, True)
            for m in STRING.finditer(text):
                s = next(g for g in m.groups() if g is not None)
                # A string that runs shell commands: `source ... && cmd`, or a command line `cmd -x ...`.
                if "&&" in s or s.startswith("source ") or re.match(r"^(ros[a-z]+|catkin_\w+|python) ", s):
                    for w in shell_commands(s):
                        add(w, f)
        for m in ABS_PATH.finditer(text):
            add(m.group(1), f, True)
    return uses, certain


def test_every_command_the_code_runs_comes_from_the_bootstrap_packages() -> None:
    uses, certain = commands_used()
    assert "roscore" in uses and "rosrun" in uses and "catkin_make" in uses and "/usr/bin/chromium" in uses, \
        "the command scan lost track of the code"
    pkgs = closure()
    env_path = f"{ROOT / '.venv' / 'bin'}:/usr/bin:{os.environ.get('PATH', '')}"
    problems, checked = [], {}
    for cmd, files in sorted(uses.items()):
        if cmd in PREREQUISITES or cmd in SHELL_WORDS:
            continue
        path = cmd if cmd.startswith("/") else shutil.which(cmd, path=env_path)
        if path is None or not os.path.exists(path):
            if cmd in certain:
                problems.append(f"{cmd} (used in {', '.join(sorted(files))}) is not installed")
            continue  # not a command (a word that looked like one)
        if str(Path(path).resolve()).startswith(str(ROOT)):
            continue  # the project's own (the venv's python, scripts)
        pkg = owner(path)
        checked[cmd] = pkg
        if pkg is None:
            problems.append(f"{cmd} -> {path} is not from any Debian package (used in {', '.join(sorted(files))})")
        elif pkg not in pkgs:
            problems.append(f"{cmd} -> {path} is in Debian package {pkg}, which scripts/apt-packages.txt "
                            f"does not install (used in {', '.join(sorted(files))})")
    print("commands checked:", json.dumps(checked, sort_keys=True))
    assert not problems, "\n".join(problems)


# --- Python modules ---------------------------------------------------------------------------------------

IMPORT = re.compile(r"^\s*(?:from\s+([A-Za-z_]\w*)[\w.]*\s+import\b|import\s+([A-Za-z_][\w.]*(?:\s*,\s*[A-Za-z_][\w.]*)*))",
                    re.M)


def python_files() -> list[Path]:
    out = []
    for f in project_files():
        if f.suffix == ".py":
            out.append(f)
        elif not f.suffix and f.read_bytes()[:64].startswith(b"#!") and b"python" in f.read_bytes()[:64]:
            out.append(f)
    return out


def modules_used() -> dict[str, set[str]]:
    uses: dict[str, set[str]] = {}
    for f in python_files():
        for m in IMPORT.finditer(f.read_text()):
            names = [m.group(1)] if m.group(1) else [n.strip().split(".")[0] for n in m.group(2).split(",")]
            for n in names:
                uses.setdefault(n, set()).add(str(f.relative_to(ROOT)))
    return uses


RESOLVE = """
import importlib.util, json, sys
out = {}
for name in sys.argv[1:]:
    try:
        spec = importlib.util.find_spec(name)
    except Exception as e:
        out[name] = "error: " + str(e)
        continue
    if spec is None:
        out[name] = None
    elif spec.origin not in (None, "built-in", "frozen", "namespace"):
        out[name] = spec.origin
    elif spec.submodule_search_locations:
        out[name] = list(spec.submodule_search_locations)[0]
    else:
        out[name] = spec.origin
print(json.dumps(out))
"""


def test_every_debian_python_module_the_code_imports_comes_from_the_bootstrap_packages() -> None:
    uses = modules_used()
    assert {"rospy", "rosgraph", "tornado", "yaml"} <= set(uses), "the import scan lost track of the code"
    local = {p.stem for p in python_files()} | {p.name for p in ROOT.glob("ros_backend/src/*/src/*")} | {"sim"}
    names = sorted(n for n in uses if n not in local)
    r = subprocess.run(["bash", "-c", 'source scripts/ros-env.sh && python -c "$0" "$@"', RESOLVE, *names], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    where = json.loads(r.stdout.strip().splitlines()[-1])
    # ROS 2's modules (rclpy, the rosidl packages) live in .venv-ros2, from requirements-ros2.txt: the ROS 2 side
    # imports them there (scripts/ros2-env.sh), never in the ROS 1 environment.
    ros2_only = [n for n in names if where.get(n) is None]
    if ros2_only:
        r2 = subprocess.run(["bash", "-c", 'source scripts/ros2-env.sh && python -c "$0" "$@"', RESOLVE, *ros2_only],
                            cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert r2.returncode == 0, r2.stderr
        where.update({k: v for k, v in json.loads(r2.stdout.strip().splitlines()[-1]).items() if v is not None})
    pkgs = closure()
    problems, checked = [], {}
    for name in names:
        origin = where.get(name)
        if origin is None:
            problems.append(f"import {name} (in {', '.join(sorted(uses[name]))}) does not resolve")
            continue
        if origin in ("built-in", "frozen") or origin.startswith("error:") or origin.startswith(str(ROOT)):
            continue  # interpreter built-ins, the project's own and the venv's (requirements.txt)
        pkg = owner(origin)
        checked[name] = pkg
        if pkg is None:
            problems.append(f"import {name} -> {origin}: not from a Debian package nor the venv")
        elif pkg not in pkgs:
            problems.append(f"import {name} -> {origin} is in Debian package {pkg}, which scripts/apt-packages.txt "
                            f"does not install (used in {', '.join(sorted(uses[name]))})")
    print("modules checked:", json.dumps(checked, sort_keys=True))
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("pkg,command", [("catkin", "catkin_make"), ("rosbash", "rosrun")])
def test_the_owners_a_hand_filled_machine_hid_are_in_the_list(pkg: str, command: str) -> None:
    assert owner(shutil.which(command) or f"/usr/bin/{command}") == pkg
    assert pkg in closure()
