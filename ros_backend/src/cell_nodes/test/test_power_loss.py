"""A crash or a power cut at any moment of a save: the parameters CSV with its rotated backups (parameters/store.py,
csvfile.write_csv) and the routine files (routines/store.py save and delete). Plain Python, no ROS.

A child process (power_loss_child.py) writes through the real store class and prints a line after each write the
store acknowledged; the test kills it with SIGKILL at a random moment, KILLS times per store, each time after a random
number of writes (0 to MOST_WRITES_BEFORE_KILL) plus a random fraction of a write. After each kill:
- every file (the CSV and each backup; each routine file) is exactly its content before or after the write in flight,
  byte for byte: never torn, never missing while it should exist, no name left over;
- so the last acknowledged write is on disk;
- a temp file the kill left does not break loading (the store is read with it still there), and starting the store
  again removes it;
- the store loads again on what is there, with no problem;
- each acknowledged write made itself durable before its acknowledgement: a temp file's data synced before it took
  its final name, the directory synced after the last change of a name that counts (a SIGKILL alone cannot show this:
  the page cache survives it, a power cut does not).
The next child starts on what the kill left. POWER_LOSS_SEED=<n> repeats a run (the seed is printed).
"""
from __future__ import annotations

import json
import os
import random
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Optional

import pytest

import power_loss_child as child
from cell_nodes.parameters.csvfile import backup_names, read_csv, render
from cell_nodes.parameters.store import ParameterStore
from cell_nodes.routines.model import encode
from cell_nodes.routines.store import RoutineStore

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
KILLS = 40
MOST_WRITES_BEFORE_KILL = 20
OPS_PER_CHILD = 200           # more than a child lives to do
CHILD_TIMEOUT_S = 20.0

NOTE = 'a note, "quoted"\nover lines; ' * 800   # parameter values to cut from: the CSV quotes them
State = dict[str, bytes]      # a final file's name -> its content; a file that does not exist is not in it


def is_temp(path: str) -> bool:
    """Both stores' temp files are dot files (never a routine name, never the CSV or a backup)."""
    return os.path.basename(path).startswith(".")


def snapshot(directory: Path) -> tuple[State, list[str]]:
    finals: State = {}
    temps: list[str] = []
    for entry in os.scandir(directory):
        if is_temp(entry.name):
            temps.append(entry.name)
        else:
            finals[entry.name] = Path(entry.path).read_bytes()
    return finals, sorted(temps)


def durability_problems(events: list[list[str]]) -> list[str]:
    """What a power cut right after the acknowledgement could undo, from one write's fsync/rename/link/unlink calls."""
    problems: list[str] = []
    synced: set[str] = set()
    unsynced_dirs: dict[str, str] = {}   # directory -> the name change in it not yet synced
    for kind, *paths in events:
        if kind == "fsync":
            synced.add(paths[0])
        elif kind == "fsync-dir":
            unsynced_dirs.pop(paths[0], None)
        else:
            src, dst = paths[0], paths[-1]
            if kind in ("replace", "rename", "link") and is_temp(src) and src not in synced:
                problems.append(f"{kind} {os.path.basename(src)} -> {os.path.basename(dst)} before its data was "
                                "synced")
            if not is_temp(dst):   # removing a temp file need not survive a power cut
                unsynced_dirs[os.path.dirname(dst)] = f"{kind} {' -> '.join(os.path.basename(p) for p in paths)}"
    problems += [f"{change}: its directory not synced before the acknowledgement" for change in unsynced_dirs.values()]
    return problems


class Parameters:
    """The CSV and its three backups; each write changes both parameters (the note's length 0 to 6000 characters)."""

    name = "parameters"

    def __init__(self, directory: Path, rng: random.Random) -> None:
        self.dir, self.rng = directory, rng
        self.config = child.parameters_config()
        self.path = directory / self.config.csv
        self.files = [self.path.name] + [os.path.basename(n) for n in backup_names(str(self.path))]
        self.counter = 0
        store = ParameterStore(self.config, str(self.path))
        store.start()
        for op in self.ops({}, 3):   # the CSV and every backup exist from the start
            assert store.set(op.items()).success

    def ops(self, state: State, n: int) -> list[dict[str, str]]:
        out = []
        for _ in range(n):
            self.counter += 1
            start = self.rng.randrange(len(NOTE) // 2)
            note = f"{self.counter}: {NOTE[start:start + self.rng.randrange(6000)]}"
            out.append({"counter": str(self.counter), "note": note})
        return out

    def apply(self, state: State, op: dict[str, str]) -> State:
        """One save: each backup takes the next newer one's content, <csv>.bak the CSV's, the CSV the new values."""
        new = dict(state)
        for older, newer in zip(self.files[1:], self.files[:-1]):
            if newer in state:
                new[older] = state[newer]
        new[self.files[0]] = render(self.config.items, op)
        return new

    def check_loads(self, state: State) -> None:
        result = read_csv(str(self.path), self.config.items, self.config.csv)   # temp files (if any) still there
        assert result.problems == [] and render(self.config.items, result.texts) == state[self.files[0]]
        store = ParameterStore(self.config, str(self.path))
        store.start()
        assert store.problems == [] and store.texts == result.texts


class Routines:
    """Routine files: saves over an existing one, new ones (overwrite false: a hard link), deletes; 1 to 80 steps."""

    name = "routines"
    NAMES = ("pick", "place two", "home.v2", "x")

    def __init__(self, directory: Path, rng: random.Random) -> None:
        self.dir, self.rng = directory, rng
        self.serial = 0
        store = RoutineStore(str(directory))
        for op in self.ops({}, 3):
            child.routine_op(store, op)

    def _save(self, name: str, overwrite: bool) -> dict[str, Any]:
        self.serial += 1
        return {"op": "save", "name": name, "overwrite": overwrite, "serial": self.serial,
                "steps": self.rng.randrange(1, 80)}

    def ops(self, state: State, n: int) -> list[dict[str, Any]]:
        names = {f[:-len(".json")] for f in state}
        out = []
        for _ in range(n):
            name = self.rng.choice(self.NAMES)
            if name not in names:
                out.append(self._save(name, overwrite=False))
                names.add(name)
            elif self.rng.random() < 0.3:
                out.append({"op": "delete", "name": name})
                names.discard(name)
            else:
                out.append(self._save(name, overwrite=True))
        return out

    def apply(self, state: State, op: dict[str, Any]) -> State:
        new = dict(state)
        if op["op"] == "delete":
            del new[op["name"] + ".json"]
        else:
            new[op["name"] + ".json"] = encode(child.routine(op))
        return new

    def check_loads(self, state: State) -> None:
        store = RoutineStore(str(self.dir))
        listed = store.list()   # temp files (if any) still there
        assert {r.name + ".json": r.error for r in listed} == {f: "" for f in state}
        assert all(encode(r) == state[r.name + ".json"] for r in listed)
        store.remove_temp_files()   # what routines_node does at start


class Child:
    """One child process; its stdout read line by line without blocking past a deadline."""

    def __init__(self, kind: str, directory: Path, ops_file: Path) -> None:
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(SRC), str(HERE), os.environ.get("PYTHONPATH", "")]))
        # -S: the child needs no site-packages, and starts faster without them
        self.proc = subprocess.Popen([sys.executable, "-S", str(HERE / "power_loss_child.py"), kind, str(directory),
                                      str(ops_file)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        self.lines: list[str] = []
        self._buf = b""

    def next_line(self, deadline: float) -> Optional[str]:
        """The next line, None at the end of its output."""
        while b"\n" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                self.proc.kill()
                raise AssertionError(f"the child said nothing for {CHILD_TIMEOUT_S} s; its lines: {self.lines[-3:]}")
            if select.select([self.proc.stdout], [], [], left)[0]:
                chunk = os.read(self.proc.stdout.fileno(), 1 << 16)
                if not chunk:
                    return None
                self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        self.lines.append(line.decode())
        return self.lines[-1]

    def kill(self) -> None:
        """SIGKILL, then every line it printed before it died."""
        self.proc.kill()
        self.proc.wait(CHILD_TIMEOUT_S)
        while self.next_line(time.monotonic() + CHILD_TIMEOUT_S) is not None:
            pass
        if self._buf:
            self.lines.append(self._buf.decode())   # a line cut short by the kill: not an acknowledgement
        self.proc.stdout.close()
        self.stderr = self.proc.stderr.read().decode(errors="replace")
        self.proc.stderr.close()


def which_version(name: str, content: Optional[bytes], states: list[State]) -> str:
    if content is None:
        return "missing"
    found = [i for i, s in enumerate(states) if s.get(name) == content]
    if not found:
        return f"{len(content)} bytes that no write of this child or before it wrote"
    return f"{len(content)} bytes, as after write {found[-1] - 1}" if found[-1] else \
        f"{len(content)} bytes, as before this child's first write"


@pytest.mark.parametrize("kind", [Parameters, Routines], ids=lambda k: k.name)
def test_a_kill_at_any_moment_leaves_the_old_or_the_new_file(kind, tmp_path: Path) -> None:
    seed = int(os.environ.get("POWER_LOSS_SEED") or random.randrange(1 << 30))
    rng = random.Random(seed)
    where = f"{kind.name}, POWER_LOSS_SEED={seed}"
    directory = tmp_path / "store"
    directory.mkdir()
    store = kind(directory, rng)
    ops_file = tmp_path / "ops.json"
    state, temps = snapshot(directory)
    assert temps == []
    t_start = time.monotonic()
    write_s = 0.005   # a write's duration, learnt from the children
    acknowledged = inside = mid_write = after_write = left_temp = 0
    for k in range(KILLS):
        ops = store.ops(state, OPS_PER_CHILD)
        ops_file.write_text(json.dumps(ops))
        writes_before_kill = rng.randrange(MOST_WRITES_BEFORE_KILL + 1)
        c = Child(kind.name, directory, ops_file)
        deadline = time.monotonic() + CHILD_TIMEOUT_S
        t_ready = None
        while True:   # until the child acknowledged `writes_before_kill` writes (or is ready, for 0)
            line = c.next_line(deadline)
            assert line is not None and line.split(" ")[0] in ("ready", "ack"), \
                f"{where}: the child ended: {c.lines[-3:]}\n{c.proc.stderr.read().decode(errors='replace')}"
            if line == "ready":
                t_ready = time.monotonic()
            if len(c.lines) == writes_before_kill + 1:
                break
        if writes_before_kill:
            write_s = 0.7 * write_s + 0.3 * (time.monotonic() - t_ready) / writes_before_kill
        time.sleep(rng.uniform(0, 1.5 * write_s))   # the random moment within the next write(s): not a condition
        c.kill()
        assert c.proc.returncode == -signal.SIGKILL, f"{where}: the child ended by itself:\n{c.stderr}"
        acks = [line.split(" ", 2) for line in c.lines if line.startswith("ack ")]
        assert [int(a[1]) for a in acks] == list(range(len(acks))), f"{where}: acknowledgements {c.lines}"
        for i, (_, _, events) in enumerate(acks):
            problems = durability_problems(json.loads(events))
            assert not problems, f"{where}, kill {k}: write {i} was acknowledged before it was durable: {problems}"

        done = len(acks)
        states = [state]
        for op in ops[:done + 1]:
            states.append(store.apply(states[-1], op))
        before, after = states[done], states[done + 1]
        got, temps = snapshot(directory)
        for name in sorted(set(before) | set(after) | set(got)):
            assert got.get(name) in (before.get(name), after.get(name)), (
                f"{where}, kill {k} after {done} acknowledged writes: {name} is "
                f"{which_version(name, got.get(name), states)}; expected "
                f"{which_version(name, before.get(name), states)} or {which_version(name, after.get(name), states)}")
        acknowledged += done
        mid_write += got not in (before, after)
        after_write += got == after != before
        left_temp += bool(temps)
        inside += got != before or bool(temps)

        store.check_loads(got)
        again, temps_after = snapshot(directory)
        assert temps_after == [], f"{where}, kill {k}: starting the store again left {temps_after} (the kill: {temps})"
        changed = [n for n in sorted(set(again) | set(got)) if again.get(n) != got.get(n)]
        assert changed == [], f"{where}, kill {k}: starting the store again changed {changed}"
        state = got
    took = time.monotonic() - t_start
    print(f"\n{where}: {KILLS} kills in {took:.1f} s, {acknowledged} acknowledged writes (about "
          f"{write_s * 1000:.1f} ms each); {inside} kills caught a write in progress; they left a write half done "
          f"(some files old, some new) {mid_write} times, a write done but not acknowledged {after_write} times, "
          f"temp files {left_temp} times")
    assert inside >= KILLS // 10, f"{where}: only {inside} kills caught a write in progress: the test proved little"
