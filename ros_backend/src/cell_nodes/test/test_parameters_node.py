"""The parameters node end to end, on ROS 1 (roscore + `rosrun cell_nodes parameters_node`) and on ROS 2 (the same
body under .venv-ros2), with the demo cell and a temporary DATA_DIR, used over ROS the way the BFF relays the page's calls: get (the CSV created from the defaults), a valid set
(the CSV, the latched topic and get all have it), a set with one bad field (nothing written, the field named), a hand
edit picked up, and a restart that reads the saved values."""
from __future__ import annotations

import os
import tempfile
import threading
from pathlib import Path
from typing import Iterator

import pytest
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node, peer

CELL = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
RECIPE = 'Bügel, "links" ✓'


class Values:
    """Every /cell/parameters/values message, as {id: value}."""

    def __init__(self) -> None:
        from cell_msgs.msg import ParameterValues
        self.history: list[dict[str, str]] = []
        self.messages: list[str] = []
        self.codes: list[str] = []
        self._lock = threading.Lock()
        self.sub = peer().subscribe("/cell/parameters/values", ParameterValues, self._cb, queue_size=20,
                                    latched=True)

    def _cb(self, msg, _sender: str) -> None:
        with self._lock:
            self.history.append({p.id: p.value for p in msg.parameters})
            self.messages.append(msg.message)
            self.codes.append(msg.code)

    def last(self) -> dict[str, str]:
        with self._lock:
            return dict(self.history[-1]) if self.history else {}


def _start(data_dir: str) -> Nodes:
    nodes = Nodes()
    nodes.run("parameters", "parameters_node", f"_cell_config:={CELL}", "_check_period_s:=0.2",
              "__name:=parameters_test", env=dict(os.environ, DATA_DIR=data_dir))
    return nodes


@pytest.fixture(scope="module")
def data_dir(ros_graph: str) -> Iterator[Path]:
    client_node("parameters_test_client")
    with tempfile.TemporaryDirectory(prefix="parameters-data-") as d:
        yield Path(d)


def test_get_set_refuse_hand_edit_and_restart(data_dir: Path) -> None:
    from cell_msgs.msg import ParameterValue
    from cell_msgs.srv import GetParameters, SetParameters

    items = yaml.safe_load(CELL.read_text())["parameters"]["items"]
    ids = [i["id"] for i in items]
    csv = data_dir / "parameters.csv"
    first = _start(str(data_dir))
    try:
        first.wait_ready("/cell/parameters/set")
        get = peer().client("/cell/parameters/get", GetParameters)
        set_ = peer().client("/cell/parameters/set", SetParameters)

        # --- get: every item with its definition; the CSV was created from the defaults
        reply = get()
        assert reply.success and reply.message == ""
        assert [p.id for p in reply.parameters] == ids
        by_id = {p.id: p for p in reply.parameters}
        ah = by_id["approach_height"]
        assert (ah.category, ah.label, ah.type, ah.unit, ah.value, ah.default_value) == \
               ("Motion", "Approach height", "float", "mm", "100", "100")
        assert (ah.has_min, ah.has_max, ah.min, ah.max, ah.decimals) == (True, True, 5.0, 200.0, 1)
        assert list(by_id["gripper_type"].options) == ["parallel", "vacuum", "magnetic"]
        assert by_id["verify_placement"].value == "true" and not by_id["verify_placement"].has_min
        assert by_id["recipe_name"].max_length == 64 and by_id["parts_per_cycle"].decimals == -1
        assert csv.read_text().startswith("id,value,unit,category,label\napproach_height,100,mm,Motion,")

        values = Values()
        wait_for(lambda: values.last().get("approach_height") == "100", 10, what="the latched values")

        # --- a valid set: saved, on the topic, read back by get
        reply = set_(changes=[ParameterValue(id="approach_height", value="60.5"),
                              ParameterValue(id="recipe_name", value=RECIPE),
                              ParameterValue(id="parts_per_cycle", value="3")])  # unchanged: not counted
        assert (reply.success, reply.message, list(reply.errors)) == (True, "saved 2 parameters", [])
        assert (reply.code, [(kv.key, kv.value) for kv in reply.params]) == ("parameters.saved", [("count", "2")])
        assert "approach_height,60.5,mm," in csv.read_text(encoding="utf-8")
        assert '"Bügel, ""links"" ✓"' in csv.read_text(encoding="utf-8")
        assert (data_dir / "parameters.csv.bak").exists()
        wait_for(lambda: values.last().get("recipe_name") == RECIPE, 5, what="the new values on the topic")
        assert values.last()["approach_height"] == "60.5"
        got = {p.id: p.value for p in get().parameters}
        assert got["approach_height"] == "60.5" and got["recipe_name"] == RECIPE

        # --- one bad field: nothing written, the field named
        before = csv.read_bytes()
        published = len(values.history)
        reply = set_(changes=[ParameterValue(id="approach_height", value="250"),
                              ParameterValue(id="parts_per_cycle", value="4")])
        assert not reply.success
        assert [(e.id, e.message) for e in reply.errors] == \
               [("approach_height", "Approach height: 250 mm is above the maximum 200 mm")]
        assert reply.message == "nothing saved: 1 invalid value: Approach height: 250 mm is above the maximum 200 mm"
        # said with codes over ROS, for the app to say in the user's language (issue 29)
        field = {kv.key: kv.value for kv in reply.errors[0].params}
        assert reply.errors[0].code == "parameters.above_max" and field["label"] == "Approach height"
        assert (field["value.code"], field["value.number"], field["max.number"]) == ("parameters.quantity", "250", "200")
        assert reply.code == "parameters.nothing_saved_one"
        assert {kv.key: kv.value for kv in reply.params}["errors.code"] == "parameters.above_max"
        assert csv.read_bytes() == before
        assert {p.id: p.value for p in get().parameters}["parts_per_cycle"] == "3"
        reply = set_(changes=[ParameterValue(id="../../etc/passwd", value="x")])
        assert not reply.success and reply.errors[0].message == "unknown parameter '../../etc/passwd'"

        # --- a hand edit is picked up and published; a bad one is reported and its default used
        csv.write_text(csv.read_text(encoding="utf-8").replace("parts_per_cycle,3,", "parts_per_cycle,7,")
                       .replace("gripper_type,parallel,", "gripper_type,suction,"), encoding="utf-8")
        wait_for(lambda: values.last().get("parts_per_cycle") == "7", 5, what="the hand edit on the topic")
        assert len(values.history) == published + 1  # the edit came next: nothing was republished for a refusal
        reply = get()
        assert reply.message == ("1 problem in parameters.csv: line 4: Gripper type: 'suction' is not one of "
                                 "parallel, vacuum, magnetic; default 'parallel' used")
        wait_for(lambda: values.messages[-1] == reply.message, 5, what="the problem on the topic")
        # said with a code on both, the problem nested (issue 29)
        assert reply.code == values.codes[-1] == "parameters.file_problems_one"
        assert {kv.key: kv.value for kv in reply.params}["problems.why.code"] == "parameters.not_option"
        assert {p.id: p.value for p in reply.parameters}["gripper_type"] == "parallel"
    finally:
        first.stop()
    first.check()
    assert "Gripper type: 'suction' is not one of" in first.output("parameters")  # the node logged the warning

    # --- a restart reads the saved values
    again = _start(str(data_dir))
    try:
        again.wait_ready("/cell/parameters/set")
        got = {p.id: p.value for p in get().parameters}
        assert (got["approach_height"], got["recipe_name"], got["parts_per_cycle"]) == ("60.5", RECIPE, "7")
    finally:
        again.stop()
    again.check()
