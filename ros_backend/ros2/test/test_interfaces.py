"""Our interfaces for ROS 2: the public packages' copies hash as the public ones, ours are built from the ROS 1
definitions. Runs under ROS 2 (scripts/test-all.sh), after the bootstrap's ros2 stage built the prefix."""
from __future__ import annotations

import importlib
import json
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
PREFIX = ROOT / "ros_backend" / "install-ros2"
sys.path.insert(0, str(ROOT / "ros_backend" / "ros2"))
from build_interfaces import adapt_line, dependencies  # noqa: E402

# RIHS01 type hashes of the public Jazzy definitions, computed by rosidl from ros-controls/control_msgs at tag 5.8.0
# (the jazzy branch) and RobotWebTools/rosbridge_suite's ros2 branch (rosapi_msgs 2.1.0). A real
# joint_trajectory_controller only talks to a FollowJointTrajectory client whose hashes are these.
PUBLIC_HASHES = {
    "control_msgs/action/FollowJointTrajectory": "RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
    "control_msgs/msg/JointComponentTolerance": "RIHS01_739ea7566931944d33830fa10f1bf5e7a7fbdc3172bce7a7eaac642bd6e3ffa4",
    "control_msgs/msg/JointTolerance": "RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
    "control_msgs/msg/JointTrajectoryControllerState": "RIHS01_51d8dd89cc624cbe9daaeeb4d80d6de9b86168ffdc3be41fefc0953e3c26e480",
    "rosapi_msgs/msg/TypeDef": "RIHS01_dcd2549139d3fdb432e7f925fe79e9fb4f02889c79be45f7482c346706734928",
    "rosapi_msgs/srv/DeleteParam": "RIHS01_54f2315f16ed27a86b8c3c1cb8fb4892f450626aff4dc943444aca175bb0f16c",
    "rosapi_msgs/srv/GetActionServers": "RIHS01_58ddbf4edbdd50fd830e700d464b40c82bd49fb0e48925a4638096f478bf3275",
    "rosapi_msgs/srv/GetParam": "RIHS01_29ba73849cec56f12f7c13fe15f701e9a2cea11e19a20f2d683937489716a641",
    "rosapi_msgs/srv/GetParamNames": "RIHS01_ce7a256c93f4220670317784439bd9bc4f9ec91ab903ac46c98c578f8d01b99e",
    "rosapi_msgs/srv/GetROSVersion": "RIHS01_526058384b92d9d5a46cadafdcdfadddc28aa53c593a1ce174bdc36e714cb097",
    "rosapi_msgs/srv/GetTime": "RIHS01_9bdff3e15f979a05f6d2b61df22cd6a15374519e34071b9096b4ba49470be7f3",
    "rosapi_msgs/srv/HasParam": "RIHS01_8f54c33a053f6beafada0bc9dec5db04a07b3d4b7da94a6b6244ebcef942ac75",
    "rosapi_msgs/srv/MessageDetails": "RIHS01_99fcd78297d23c60568094c43ce511a7c1059e8030896947b403c743f54da20a",
    "rosapi_msgs/srv/NodeDetails": "RIHS01_37ad3ea5a79a1b09aa63efbb8267acabbac80e50d7fa61f5a14e197fff92d7d9",
    "rosapi_msgs/srv/Nodes": "RIHS01_82294054ac447255c9623f0cfb586a2f8317cb5c3c3fbb91bf178725c7138115",
    "rosapi_msgs/srv/Publishers": "RIHS01_2d61a1ef6383f38478c2d18c849bf14567f29e7dcc8c5d1a63b921bff4673071",
    "rosapi_msgs/srv/ServiceNode": "RIHS01_d2cef0f6cc6b9ea76c335860503d2e8573b49f9c964ae83665731cbb7b4ee4ea",
    "rosapi_msgs/srv/ServiceProviders": "RIHS01_482ab0294864029a2bc34206bba62b5b734cabf4fd4a41487f5ed0dea60e526e",
    "rosapi_msgs/srv/ServiceRequestDetails": "RIHS01_ec8a46b58297ac8d24aa8208ad3b20ebbe75371ddde50e54a652d665a0534ba9",
    "rosapi_msgs/srv/ServiceResponseDetails": "RIHS01_489f3fdc308c55b6edd8c8c6f3ca4cbab89ed890bf6ae361140e37015a7c1818",
    "rosapi_msgs/srv/ServiceType": "RIHS01_ff6afe2d76bfc5eb9cd55cf74710aa0543ffa9f4c7956ab2af8683bd91691fd9",
    "rosapi_msgs/srv/Services": "RIHS01_5028bd508d397217b7ca29bfaad9e54af6427733706c3efd1638edd56b49409e",
    "rosapi_msgs/srv/ServicesForType": "RIHS01_3f9b7301fc30a8100179b0ee34d7a855f0b6da4a837751f3a9a426c56c0cb105",
    "rosapi_msgs/srv/SetParam": "RIHS01_34a4918963ca296fb22c59607953e426afb3a41c4c13150bf8697d03343080cb",
    "rosapi_msgs/srv/Subscribers": "RIHS01_d211105eea00000ba121c6073c7390daae8fcc6a21dbae6c5500e5be809853cf",
    "rosapi_msgs/srv/TopicType": "RIHS01_db0aea255b470fc8897cc2e0bd915c44be1c76c47b778d2444d7ca5b55fd69df",
    "rosapi_msgs/srv/Topics": "RIHS01_dc3ce17920796aae9a04c5421e43c904671d1854eaf0112721aa465415f06b53",
    "rosapi_msgs/srv/TopicsAndRawTypes": "RIHS01_c900dd8bf8cba118ceaf9291072d1d957a69459fc8601146923e8375ed0a7947",
    "rosapi_msgs/srv/TopicsForType": "RIHS01_30f193f32508dd6c9ef428326f00d0aef2f585d15436fec65b262e6ddce20c96",}


def built_hashes(pkg: str) -> dict:
    out = {}
    for path in sorted((PREFIX / "share" / pkg).glob("*/*.json")):
        for entry in json.loads(path.read_text())["type_hashes"]:
            out[entry["type_name"]] = entry["hash_string"]
    return out


@pytest.mark.parametrize("pkg", ["control_msgs", "rosapi_msgs"])
def test_public_interfaces_hash_as_the_public_package(pkg: str) -> None:
    built = built_hashes(pkg)
    expected = {k: v for k, v in PUBLIC_HASHES.items() if k.startswith(pkg + "/")}
    assert expected and {k: built.get(k) for k in expected} == expected


def test_the_types_they_use_are_the_installed_public_ones() -> None:
    """Every type a FollowJointTrajectory goal names (trajectory_msgs, builtin_interfaces, std_msgs...) hashes as
    the PyPI packages of ROS 2 Jazzy ship it."""
    refs = built_hashes("control_msgs")
    venv_share = ROOT / ".venv-ros2" / "share"
    checked = 0
    for name, digest in refs.items():
        pkg, kind, type_ = name.split("/")
        shipped = venv_share / pkg / kind / f"{type_}.json"
        if pkg != "control_msgs" and shipped.exists():
            assert json.loads(shipped.read_text())["type_hashes"][0]["hash_string"] == digest, name
            checked += 1
    assert checked >= 5


def test_cell_msgs_is_built_from_every_ros1_definition_with_ros2_time() -> None:
    src = ROOT / "ros_backend" / "src" / "cell_msgs"
    for kind in ("msg", "srv", "action"):
        module = importlib.import_module(f"cell_msgs.{kind}")
        for path in (src / kind).glob(f"*.{kind}"):
            assert hasattr(module, path.stem), f"cell_msgs/{kind}/{path.stem} not built for ROS 2"
    from cell_msgs.msg import OperationMode
    assert OperationMode.get_fields_and_field_types()["stamp"] == "builtin_interfaces/Time"


@pytest.mark.parametrize("line,expected", [
    ("time stamp", "builtin_interfaces/Time stamp"),
    ("duration[] waits  # comment", "builtin_interfaces/Duration[] waits  # comment"),
    ("Header header", "std_msgs/Header header"),
    ("  time[3] t", "  builtin_interfaces/Time[3] t"),
    ("uint8 IDLE=0", "uint8 IDLE=0"),
    ("# time in a comment", "# time in a comment"),
    ("---", "---"),
    ("string timestamp", "string timestamp"),
])
def test_ros1_syntax_is_adapted_where_the_generations_differ(line: str, expected: str) -> None:
    assert adapt_line(line) == expected


def test_ros1_only_dependencies_are_dropped(tmp_path: pathlib.Path) -> None:
    f = tmp_path / "X.action"
    f.write_text("actionlib_msgs/GoalStatus s\ndiagnostic_msgs/KeyValue kv\n---\n---\n")
    assert dependencies([f], "cell_msgs") == {"diagnostic_msgs", "action_msgs"}
