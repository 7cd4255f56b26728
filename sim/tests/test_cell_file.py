"""The sim takes its device topics and camera streams from the cell file, and refuses a bad file clearly."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from sim.__main__ import parse_args
from sim.cameras import VIEWS
from sim.cell_file import CellDevices, CellFileError, Stream, default_cell_path, devices_from, load_devices

ROOT = Path(__file__).resolve().parents[2]
CELLS = Path(__file__).resolve().parent / "cells"
RENAMED = CELLS / "renamed-topics.yaml"


def test_viewpoints_are_one_table_in_declared_order() -> None:
    assert list(VIEWS) == ["workbench", "global"]


def test_demo_cell_maps_to_the_devices_the_ui_shows() -> None:
    d = load_devices(str(ROOT / "config" / "demo-cell.yaml"))
    assert d.wrench_topics == ("/cell/wrench",)
    assert d.tactile_topics == ("/cell/tactile",)
    assert [(s.topic, s.view, s.raw, s.size) for s in d.streams] == [
        ("/cell/camera/workbench/image/compressed", "workbench", False, None),
        ("/cell/camera/global/image/compressed", "global", False, None),
        ("/cell/camera/global/image_raw", "global", True, (1280, 720))]


def test_a_wrong_stream_type_or_size_names_the_field(tmp_path) -> None:
    import yaml
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    for bad, field in (({"type": "h264"}, "video.streams[0].type"), ({"sim_size": [1280]}, "video.streams[0].sim_size")):
        doc["video"]["streams"][0].update(bad)
        path = tmp_path / "cell.yaml"
        path.write_text(yaml.safe_dump(doc))
        with pytest.raises(CellFileError, match=re.escape(field)):
            load_devices(str(path))
        for k in bad:
            del doc["video"]["streams"][0][k]


def test_renamed_cell_every_matching_sensor_and_every_stream() -> None:
    d = load_devices(str(RENAMED))
    assert d.wrench_topics == ("/robot2/ft_sensor/wrench", "/robot2/ft_sensor/wrench_copy")
    assert d.tactile_topics == ("/robot2/finger/tactile",)  # the Float64 sensor is not the sim's
    assert d.streams == (Stream("Overview", "/robot2/overview/compressed", "global"),
                         Stream("Overview again", "/robot2/overview2/compressed", "global"),
                         Stream("Bench", "/robot2/bench/compressed", "workbench"))
    assert d.views == ["workbench", "global"]


def test_streams_without_view_cycle_through_the_viewpoints() -> None:
    streams = [{"name": f"s{i}", "topic": f"/cam{i}"} for i in range(5)]
    d = devices_from({"video": {"streams": streams}})
    assert [s.view for s in d.streams] == ["workbench", "global", "workbench", "global", "workbench"]
    d = devices_from({"video": {"streams": [{"name": "only", "topic": "/c", "view": "global"}]}})
    assert d.views == ["global"]  # the workbench view is never rendered for this cell


def test_same_sensor_topic_twice_is_published_once() -> None:
    ft = {"title": "a", "kind": "time-series", "topic": "/ft", "type": "geometry_msgs/WrenchStamped"}
    assert devices_from({"sensors": [ft, dict(ft, title="b")]}).wrench_topics == ("/ft",)


@pytest.mark.parametrize("doc", [
    {"cell": {"id": "x"}},
    {"cell": {"id": "x"}, "sensors": None, "video": None},
    {"sensors": [], "video": {}},
    {"video": {"streams": []}},
    {"sensors": [{"title": "t", "topic": "/t", "type": "std_msgs/Float64"}]},
])
def test_missing_sections_mean_no_devices(doc) -> None:
    d = devices_from(doc)
    assert (d.wrench_topics, d.tactile_topics, d.streams) == ((), (), ())


def test_no_devices_fixture_file() -> None:
    d = load_devices(str(CELLS / "no-devices.yaml"))
    assert d == CellDevices(path=str(CELLS / "no-devices.yaml"))


@pytest.mark.parametrize("content, expected", [
    (None, "No such file"),
    ("sensors: [unclosed\n", "not valid YAML"),
    ("- just\n- a list\n", "not a cell file"),
    ("", "not a cell file"),
    (b"\xff\xfe\x00bad", "cannot read"),
    ("cell: {built: 2024-13-45}\n", "month must be in 1..12"),
])
def test_unreadable_file_is_a_clear_error(tmp_path: Path, content, expected: str) -> None:
    path = tmp_path / "cell.yaml"
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is not None:
        path.write_text(content)
    with pytest.raises(CellFileError) as e:
        load_devices(str(path))
    assert str(path) in str(e.value) and expected in str(e.value)
    assert str(e.value).startswith("cannot read cell file")


def test_a_directory_is_not_a_cell_file(tmp_path: Path) -> None:
    with pytest.raises(CellFileError, match="cannot read cell file"):
        load_devices(str(tmp_path))


WRENCH = "geometry_msgs/WrenchStamped"


@pytest.mark.parametrize("doc, where", [
    ({"sensors": {"title": "x"}}, "sensors: expected a list"),
    ({"sensors": ["/cell/wrench"]}, "sensors[0]: expected a mapping"),
    ({"sensors": [{"type": WRENCH}]}, "sensors[0].topic"),
    ({"sensors": [{"type": WRENCH, "topic": "cell/wrench"}]}, "sensors[0].topic"),
    ({"sensors": [{"type": WRENCH, "topic": "/cell//wrench"}]}, "sensors[0].topic"),
    ({"sensors": [{"type": WRENCH, "topic": "/cell/wrench here"}]}, "sensors[0].topic"),
    ({"sensors": [{"type": ["x"], "topic": 3}]}, None),  # an odd type is simply not the sim's
    ({"video": ["a"]}, "video: expected a mapping"),
    ({"video": {"streams": {"name": "a"}}}, "video.streams: expected a list"),
    ({"video": {"streams": [{"name": "a"}]}}, "video.streams[0].topic"),
    ({"video": {"streams": [{"topic": "/a", "view": "ceiling"}]}}, "video.streams[0].view: unknown viewpoint 'ceiling'"),
    ({"video": {"streams": [{"topic": "/a"}, {"topic": "/a"}]}}, "video.streams[1].topic: /a is already"),
    ({"sensors": [{"type": WRENCH, "topic": "/a"}, {"type": "cell_msgs/Scatter", "topic": "/a"}]},
     "tactile sensor: /a is already used by a wrench sensor"),
    ({"sensors": [{"type": WRENCH, "topic": "/a"}], "video": {"streams": [{"topic": "/a"}]}}, "video stream: /a"),
    ({"sensors": [{"type": WRENCH, "topic": "/sim/faults"}]}, "already used by the sim itself"),
])
def test_unusable_sections_name_the_field(doc, where) -> None:
    if where is None:
        devices_from(doc, "x.yaml")
        return
    with pytest.raises(CellFileError) as e:
        devices_from(doc, "x.yaml")
    assert str(e.value).startswith("cell file x.yaml: ") and where in str(e.value)


def test_unknown_view_lists_the_sims_viewpoints() -> None:
    with pytest.raises(CellFileError, match=r"the sim has: workbench, global"):
        devices_from({"video": {"streams": [{"topic": "/a", "view": "ceiling"}]}})


def test_cell_option_then_cell_config_then_demo_cell(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CELL_CONFIG", raising=False)
    assert Path(default_cell_path()) == ROOT / "config" / "demo-cell.yaml"
    assert parse_args([]).devices.path == str(ROOT / "config" / "demo-cell.yaml")
    monkeypatch.setenv("CELL_CONFIG", str(CELLS / "no-devices.yaml"))
    assert parse_args([]).devices.path == str(CELLS / "no-devices.yaml")
    opts = parse_args(["--cell", str(RENAMED)])
    assert opts.devices.path == str(RENAMED) and len(opts.devices.streams) == 3


def test_program_start_option(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CELL_CONFIG", raising=False)
    assert parse_args([]).program_start == 0.05
    assert parse_args(["--program-start", "3"]).program_start == 3.0
    with pytest.raises(SystemExit):
        parse_args(["--program-start", "-1"])


def test_cli_refuses_an_unreadable_cell_file_without_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("video: {streams: [{name: a, topic: /a, view: ceiling}]}\n")
    broken = tmp_path / "broken.yaml"
    broken.write_text("sensors:\n  - [unclosed\n")
    for args, env_cell, expected in ((["--cell", str(tmp_path / "missing.yaml")], None, "cannot read cell file"),
                                     (["--cell", str(broken)], None, "not valid YAML"),
                                     ([], str(bad), "video.streams[0].view: unknown viewpoint")):
        env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(ROOT), "ROS_MASTER_URI": "http://127.0.0.1:1"}
        if env_cell:
            env["CELL_CONFIG"] = env_cell
        r = subprocess.run([sys.executable, "-m", "sim", "--host", "127.0.0.19", "--no-ros", *args], cwd=ROOT,
                           env=env, capture_output=True, text=True, timeout=30)
        assert r.returncode == 2, r.stderr
        assert expected in r.stderr and "Traceback" not in r.stderr
        lines = [ln for ln in r.stderr.splitlines() if not ln.startswith("pybullet build time")]  # pybullet's banner
        assert len(lines) == 1 and lines[0].startswith("python -m sim: "), f"one line expected, got:\n{r.stderr}"
