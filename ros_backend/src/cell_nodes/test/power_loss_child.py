"""The child process of test_power_loss.py: writes through the real store classes until the test kills it.

    python power_loss_child.py parameters|routines DIR OPS_JSON_FILE

It starts the store on DIR (as the node does at start), prints `ready`, then runs the writes of OPS_JSON_FILE in
order and prints `ack <index> <events>` after each one the store acknowledged (returned from with success). The
events are the calls of that write that decide what a power cut right after the acknowledgement would leave (fsync of
a file or a directory, rename, link, unlink), as JSON: the test checks them, because a SIGKILL alone cannot show a
missing fsync (the page cache survives the process).

Also imported by the test for what both sides must agree on: the parameters section, how an op becomes a routine.
"""
from __future__ import annotations

import json
import os
import stat
import sys
from typing import Any

from cell_nodes.parameters.config import parse_parameters
from cell_nodes.routines.model import POSE, Routine, Step

PARAMETERS = {"parameters": {"csv": "params.csv", "items": [
    {"id": "counter", "type": "int", "label": "Counter", "category": "Test", "default": 0},
    # long enough that a file spans several pages; commas, quotes and line breaks need the CSV's quoting
    {"id": "note", "type": "string", "label": "Note", "category": "Test", "max_length": 10000, "default": ""},
]}}

EVENTS: list[list[str]] = []


def parameters_config():
    return parse_parameters(PARAMETERS)


def routine(op: dict[str, Any]) -> Routine:
    """The routine a save op writes (the test encodes the same one to know the file's bytes)."""
    base = op["serial"] % 997 / 1000.0
    steps = tuple(Step(POSE, (base, 0.1 + i / 1000.0, 0.3, 3.1416, 0.0, -base),
                       (base, -1.57, 1.57, -1.57, -1.57, i / 100.0)) for i in range(op["steps"]))
    return Routine(op["name"], group="arm", tool="", steps=steps)


def routine_op(store, op: dict[str, Any]) -> None:
    if op["op"] == "delete":
        store.delete(op["name"])
    else:
        store.save(routine(op), overwrite=op["overwrite"])


def trace_file_system_calls() -> None:
    """Record, after they succeed, the calls that make a write durable or visible (the stores call them through
    the os module, tempfile too)."""
    real = {name: getattr(os, name) for name in ("fsync", "replace", "rename", "link", "unlink")}

    def fsync(fd: int) -> None:
        path = os.readlink(f"/proc/self/fd/{fd}")
        kind = "fsync-dir" if stat.S_ISDIR(os.fstat(fd).st_mode) else "fsync"
        real["fsync"](fd)
        EVENTS.append([kind, path])

    def two_paths(name: str):
        def call(src, dst, *args, **kwargs):
            real[name](src, dst, *args, **kwargs)
            EVENTS.append([name, os.path.abspath(src), os.path.abspath(dst)])
        return call

    def unlink(path, *args, **kwargs):
        real["unlink"](path, *args, **kwargs)
        EVENTS.append(["unlink", os.path.abspath(path)])

    os.fsync = fsync
    os.replace, os.rename, os.link = two_paths("replace"), two_paths("rename"), two_paths("link")
    os.unlink = unlink


def acknowledge(index: int) -> None:
    print(f"ack {index} {json.dumps(EVENTS)}", flush=True)
    EVENTS.clear()


def run_parameters(directory: str, ops: list[dict[str, str]]) -> None:
    from cell_nodes.parameters.store import ParameterStore
    config = parameters_config()
    store = ParameterStore(config, os.path.join(directory, config.csv))
    store.start()
    assert not store.problems, store.problems
    print("ready", flush=True)
    EVENTS.clear()
    for i, op in enumerate(ops):
        result = store.set(op.items())
        if not result.success or len(result.changed) != len(op):
            raise SystemExit(f"write {i} not saved as asked: {result}")
        acknowledge(i)


def run_routines(directory: str, ops: list[dict[str, Any]]) -> None:
    from cell_nodes.routines.store import RoutineStore
    store = RoutineStore(directory)
    store.remove_temp_files()  # what routines_node does at start
    print("ready", flush=True)
    EVENTS.clear()
    for i, op in enumerate(ops):
        routine_op(store, op)
        acknowledge(i)


def main() -> None:
    kind, directory, ops_file = sys.argv[1:]
    with open(ops_file) as f:
        ops = json.load(f)
    trace_file_system_calls()
    {"parameters": run_parameters, "routines": run_routines}[kind](directory, ops)
    print("done", flush=True)


if __name__ == "__main__":
    main()
