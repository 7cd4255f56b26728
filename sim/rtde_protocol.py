"""RTDE wire format (protocol version 2): package header, package types, variable names and their types.

A package is uint16 size (including the 3-byte header) + uint8 type + payload, all big-endian.
"""
from __future__ import annotations

import struct
from typing import Any, Optional

HEADER = struct.Struct(">HB")

REQUEST_PROTOCOL_VERSION = ord("V")
GET_URCONTROL_VERSION = ord("v")
TEXT_MESSAGE = ord("M")
DATA_PACKAGE = ord("U")
CONTROL_PACKAGE_SETUP_OUTPUTS = ord("O")
CONTROL_PACKAGE_SETUP_INPUTS = ord("I")
CONTROL_PACKAGE_START = ord("S")
CONTROL_PACKAGE_PAUSE = ord("P")

# Type name -> struct format of one value.
TYPE_FORMATS = {
    "BOOL": "?", "UINT8": "B", "UINT32": "I", "UINT64": "Q", "INT32": "i", "DOUBLE": "d",
    "VECTOR3D": "3d", "VECTOR6D": "6d", "VECTOR6INT32": "6i", "VECTOR6UINT32": "6I",
}

_OUTPUTS: dict[str, str] = {
    "timestamp": "DOUBLE", "target_q": "VECTOR6D", "target_qd": "VECTOR6D", "target_qdd": "VECTOR6D",
    "target_current": "VECTOR6D", "target_moment": "VECTOR6D", "actual_q": "VECTOR6D", "actual_qd": "VECTOR6D",
    "actual_current": "VECTOR6D", "actual_current_window": "VECTOR6D", "joint_control_output": "VECTOR6D",
    "actual_TCP_pose": "VECTOR6D", "actual_TCP_speed": "VECTOR6D", "actual_TCP_force": "VECTOR6D",
    "target_TCP_pose": "VECTOR6D", "target_TCP_speed": "VECTOR6D", "actual_digital_input_bits": "UINT64",
    "joint_temperatures": "VECTOR6D", "actual_execution_time": "DOUBLE", "robot_mode": "INT32",
    "joint_mode": "VECTOR6INT32", "safety_mode": "INT32", "safety_status": "INT32",
    "actual_tool_accelerometer": "VECTOR3D", "speed_scaling": "DOUBLE", "target_speed_fraction": "DOUBLE",
    "actual_momentum": "DOUBLE", "actual_main_voltage": "DOUBLE", "actual_robot_voltage": "DOUBLE",
    "actual_robot_current": "DOUBLE", "actual_joint_voltage": "VECTOR6D", "actual_digital_output_bits": "UINT64",
    "runtime_state": "UINT32", "elbow_position": "VECTOR3D", "elbow_velocity": "VECTOR3D",
    "robot_status_bits": "UINT32", "safety_status_bits": "UINT32", "analog_io_types": "UINT32",
    "standard_analog_input0": "DOUBLE", "standard_analog_input1": "DOUBLE",
    "standard_analog_output0": "DOUBLE", "standard_analog_output1": "DOUBLE", "io_current": "DOUBLE",
    "euromap67_input_bits": "UINT32", "euromap67_output_bits": "UINT32", "euromap67_24V_voltage": "DOUBLE",
    "euromap67_24V_current": "DOUBLE", "tool_mode": "UINT32", "tool_analog_input_types": "UINT32",
    "tool_analog_input0": "DOUBLE", "tool_analog_input1": "DOUBLE", "tool_output_voltage": "INT32",
    "tool_output_current": "DOUBLE", "tool_temperature": "DOUBLE", "tcp_force_scalar": "DOUBLE",
    "output_bit_registers0_to_31": "UINT32", "output_bit_registers32_to_63": "UINT32",
    "input_bit_registers0_to_31": "UINT32", "input_bit_registers32_to_63": "UINT32",
    "payload": "DOUBLE", "payload_cog": "VECTOR3D", "payload_inertia": "VECTOR6D", "script_control_line": "UINT32",
    "ft_raw_wrench": "VECTOR6D", "joint_position_deviation_ratio": "DOUBLE", "collision_detection_ratio": "DOUBLE",
    "time_scale_source": "INT32", "tool_output_mode": "UINT8", "tool_digital_output0_mode": "UINT8",
    "tool_digital_output1_mode": "UINT8", "actual_robot_energy_consumed": "DOUBLE",
    "actual_robot_braking_energy_dissipated": "DOUBLE",
}
_INPUTS: dict[str, str] = {
    "speed_slider_mask": "UINT32", "speed_slider_fraction": "DOUBLE",
    "standard_digital_output_mask": "UINT8", "standard_digital_output": "UINT8",
    "configurable_digital_output_mask": "UINT8", "configurable_digital_output": "UINT8",
    "tool_digital_output_mask": "UINT8", "tool_digital_output": "UINT8",
    "standard_analog_output_mask": "UINT8", "standard_analog_output_type": "UINT8",
    "standard_analog_output_0": "DOUBLE", "standard_analog_output_1": "DOUBLE",
    "input_bit_registers0_to_31": "UINT32", "input_bit_registers32_to_63": "UINT32",
    "external_force_torque": "VECTOR6D",
}
for _i in range(48):
    for _table, _kind in ((_OUTPUTS, "output"), (_INPUTS, "input")):
        _table[f"{_kind}_int_register_{_i}"] = "INT32"
        _table[f"{_kind}_double_register_{_i}"] = "DOUBLE"
    _OUTPUTS[f"input_int_register_{_i}"] = "INT32"      # inputs can be read back as outputs
    _OUTPUTS[f"input_double_register_{_i}"] = "DOUBLE"
for _i in range(64, 128):
    _OUTPUTS[f"output_bit_register_{_i}"] = "BOOL"
    _INPUTS[f"input_bit_register_{_i}"] = "BOOL"
    _OUTPUTS[f"input_bit_register_{_i}"] = "BOOL"

OUTPUT_TYPES = _OUTPUTS
INPUT_TYPES = _INPUTS


def pack(ptype: int, payload: bytes = b"") -> bytes:
    return HEADER.pack(HEADER.size + len(payload), ptype) + payload


def recipe_format(types: list[str]) -> Optional[struct.Struct]:
    """A struct for a data package body (after the recipe id) with these variable types, or None if any is unknown."""
    fmt = ">"
    for t in types:
        if t not in TYPE_FORMATS:
            return None
        fmt += TYPE_FORMATS[t]
    return struct.Struct(fmt)


def flatten(types: list[str], values: list[Any]) -> list[Any]:
    out: list[Any] = []
    for t, v in zip(types, values):
        if t.startswith("VECTOR"):
            out.extend(v)
        else:
            out.append(v)
    return out


def unflatten(types: list[str], flat: tuple) -> list[Any]:
    out, i = [], 0
    for t in types:
        n = 6 if t.startswith("VECTOR6") else 3 if t.startswith("VECTOR3") else 1
        out.append(list(flat[i:i + n]) if n > 1 else flat[i])
        i += n
    return out


def parse_names(payload: bytes) -> list[str]:
    """Comma-separated variable names; clients (ur_rtde) send a trailing comma: drop empty names."""
    return [n.strip() for n in payload.decode("ascii", "replace").split(",") if n.strip()]


def text_message(text: str, source: str = "sim", level: int = 1) -> bytes:
    """RTDE v2 text message: (length-prefixed) message, source, warning level."""
    msg = text.encode()[:255]
    src = source.encode()[:255]
    return pack(TEXT_MESSAGE, bytes([len(msg)]) + msg + bytes([len(src)]) + src + bytes([level]))
