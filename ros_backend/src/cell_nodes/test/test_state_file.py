"""The nodes' small state files (cell_nodes.state_file): where they live, atomic replacement, and what a bad file
does (a clear problem, the file moved aside, a clean start; never an exception)."""
from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

from cell_nodes import state_file
from cell_nodes.state_file import Saver, StateFile, state_dir


def test_the_directory_is_the_nodes_parameter_else_data_dir_state_else_none(tmp_path: Path) -> None:
    assert state_dir(str(tmp_path / "x"), {"DATA_DIR": "/srv/cell"}) == str(tmp_path / "x")
    assert state_dir(None, {"DATA_DIR": str(tmp_path)}) == str(tmp_path / "state")
    assert state_dir("", {}) is None
    f = StateFile(None, "alarms", "alarms.mode")
    assert f.path is None and f.load().data is None and f.load().problem == ""
    f.save({"a": 1})                                             # nowhere to save: nothing happens, no error


def test_saved_data_comes_back_and_the_file_says_what_it_holds(tmp_path: Path) -> None:
    f = StateFile(str(tmp_path / "state"), "process", "process.cycles")
    assert f.load().data is None                                 # nothing saved yet: no problem either
    f.save({"next_cycle": 4, "last_cycle_s": 10.5}, now=1234.5)
    doc = json.loads(Path(f.path).read_text())
    assert doc == {"kind": "process.cycles", "version": 1, "saved_at": 1234.5,
                   "data": {"next_cycle": 4, "last_cycle_s": 10.5}}
    assert oct(os.stat(f.path).st_mode & 0o777) == "0o644"
    loaded = f.load()
    assert (loaded.data, loaded.saved_at, loaded.problem) == ({"next_cycle": 4, "last_cycle_s": 10.5}, 1234.5, "")
    assert os.listdir(tmp_path / "state") == ["process.json"]   # no temp file left
    with pytest.raises(ValueError):
        f.save({"x": float("nan")})                              # JSON cannot hold it: refused, file unchanged
    assert f.load().data == {"next_cycle": 4, "last_cycle_s": 10.5}


@pytest.mark.parametrize("content, why", [
    (b"{\"kind\": \"process.cycles\", \"vers", r"not valid JSON"),
    (b"\xff\xfe", r"not valid JSON"),
    (b"[1, 2]", r"not a JSON object"),
    (b'{"kind": "alarms.mode", "version": 1, "data": {}}', r"holds 'alarms.mode', not 'process.cycles'"),
    (b'{"kind": "process.cycles", "version": 2, "data": {}}', r"version 2, this node reads version 1"),
    (b'{"kind": "process.cycles", "version": 1, "data": [1]}', r"no `data` object"),
    (b" " * (state_file.MAX_BYTES + 1), r"larger than"),
])
def test_a_malformed_or_foreign_file_is_a_problem_moved_aside(tmp_path: Path, content: bytes, why: str) -> None:
    f = StateFile(str(tmp_path), "process", "process.cycles")
    Path(f.path).write_bytes(content)
    loaded = f.load()
    assert loaded.data is None
    assert re.search(why, loaded.problem), loaded.problem
    assert loaded.problem.startswith(f"{f.path}: ") and "starting clean" in loaded.problem
    assert f"moved to {f.path}.bad" in loaded.problem
    assert not os.path.exists(f.path) and Path(f.path + ".bad").read_bytes() == content
    assert f.load() == state_file.Loaded()                       # the next start is clean
    f.save({"ok": True})
    assert f.load().data == {"ok": True}


def test_the_features_check_refuses_stale_data_the_same_way(tmp_path: Path) -> None:
    f = StateFile(str(tmp_path), "alarms", "alarms.mode")
    f.save({"previous": "spinning"})
    loaded = f.load(lambda d: None if d["previous"] in ("idle", "running") else "previous: not a mode of this cell")
    assert loaded.data is None and "previous: not a mode of this cell; starting clean" in loaded.problem
    assert os.path.exists(f.path + ".bad")


def test_a_crash_mid_save_leaves_the_old_file_and_its_temp_file_is_removed_at_the_next_load(tmp_path: Path,
                                                                                          monkeypatch) -> None:
    f = StateFile(str(tmp_path), "process", "process.cycles")
    f.save({"next_cycle": 2})

    def power_cut(src: str, dst: str) -> None:
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(state_file.os, "replace", power_cut)
    with pytest.raises(OSError):
        f.save({"next_cycle": 3})
    monkeypatch.undo()
    assert f.load().data == {"next_cycle": 2}                    # the old file, whole
    # A temp file a real power cut left behind (written, never renamed) is not read and goes at the next load.
    leftover = tmp_path / ".tmp-process-abc.json"
    leftover.write_text("{half")
    assert f.load().data == {"next_cycle": 2} and not leftover.exists()


def test_an_unreadable_file_is_a_problem_but_is_not_moved(tmp_path: Path) -> None:
    f = StateFile(str(tmp_path), "process", "process.cycles")
    os.mkdir(f.path)                                             # reading a directory fails (also as root)
    loaded = f.load()
    assert loaded.data is None and loaded.problem.startswith(f"cannot read {f.path}: ")
    assert os.path.isdir(f.path)


def test_the_saver_writes_only_changes_and_reports_a_failure_once(tmp_path: Path) -> None:
    f = StateFile(str(tmp_path / "state"), "process", "process.cycles")
    errors: list[str] = []
    saver = Saver(f, {"n": 1}, errors.append)
    assert saver.update(lambda: {"n": 1}) is False and not os.path.exists(f.path)   # as loaded: nothing to write
    assert saver.update(lambda: {"n": 2}) is True and f.load().data == {"n": 2}
    assert saver.update(lambda: {"n": 2}) is False
    blocker = tmp_path / "blocked"
    blocker.write_text("a file where the directory should be")
    bad = Saver(StateFile(str(blocker / "state"), "process", "process.cycles"), None, errors.append)
    assert bad.update(lambda: {"n": 1}) is False and bad.update(lambda: {"n": 1}) is False
    assert len(errors) == 1 and errors[0].startswith(f"could not save {blocker / 'state' / 'process.json'}: ")
    assert Saver(StateFile(None, "p", "k")).update(lambda: {"n": 1}) is False
