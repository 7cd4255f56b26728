"""Routines and their steps, routine names, the checks a routine must pass to be saved or run, and the JSON file
format. Every check returns a message the operator can act on; nothing here touches files or the robot."""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

from ..said import Said, say
from .config import RoutinesConfig

POSE, ACTION = "pose", "action"
KINDS = (POSE, ACTION)
MAX_NAME = 64
MAX_STEPS = 1000
FORMAT_VERSION = 1
# ASCII only, by choice: the name is the file name, so it must mean the same on every file system (USB sticks,
# backups) and have one spelling (no Unicode normalisation forms, no look-alike letters).
_NAME_CHARS = re.compile(r"[A-Za-z0-9 _.\-]+")


class RoutineError(Exception):
    """A request that is refused; the message (a Said where it was said with a code) goes back to the caller as is."""


def said_of(e: Exception) -> Said:
    """A refusal's text, with its code when it was said with one."""
    return e.args[0] if e.args and isinstance(e.args[0], Said) else Said(str(e))


@dataclass(frozen=True)
class Step:
    kind: str
    pose: tuple[float, ...] = ()      # m, rad (rotation vector), base frame
    joints: tuple[float, ...] = ()    # rad, the group's joints when recorded
    tool: str = ""
    action: str = ""


@dataclass(frozen=True)
class Routine:
    name: str
    group: str = ""
    tool: str = ""
    steps: tuple[Step, ...] = ()
    modified: float = 0.0             # the file's modification time (Unix s); 0 when unknown
    error: str = ""                   # why the file cannot be read or run; "" when it can


def _shown(name: str) -> str:
    """The name for a message: quoted, control characters escaped, long names cut."""
    return repr(name if len(name) <= 80 else name[:77] + "...")


def name_problem(name: Any) -> Optional[Said]:
    """Why `name` cannot be a routine name, or None: 1-64 ASCII letters, digits, space, - _ . ; not starting with a
    dot (hidden files, `.`/`..`) and not starting or ending with a space."""
    if not isinstance(name, str):
        return say("routines.name_not_text", "a routine name must be text, got {kind}", kind=type(name).__name__)
    if not name:
        return say("routines.name_needed", "a routine needs a name")
    if len(name) > MAX_NAME:
        return say("routines.name_too_long", "routine name {name} is too long ({length} characters, at most {max})",
                   name=_shown(name), length=len(name), max=MAX_NAME)
    if not _NAME_CHARS.fullmatch(name):
        return say("routines.name_chars", "invalid routine name {name}: use letters, digits, space, - _ .",
                   name=_shown(name))
    if name.startswith("."):
        return say("routines.name_dot", "invalid routine name {name}: it must not start with a dot", name=_shown(name))
    if name != name.strip(" "):
        return say("routines.name_space", "invalid routine name {name}: it must not start or end with a space",
                   name=_shown(name))
    return None


def check_name(name: Any) -> str:
    problem = name_problem(name)
    if problem:
        raise RoutineError(problem)
    return name


def _finite(values: Sequence[Any]) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def format_pose(pose: Sequence[float]) -> Said:
    """`x 412.3, y -120.0, z 230.5 mm, rx 3.142, ry 0.000, rz 0.000 rad` (+ 0.0: no "-0.0")."""
    x, y, z, rx, ry, rz = (float(v) + 0.0 for v in pose)
    return say("routines.pose_full", "x {x}, y {y}, z {z} mm, rx {rx}, ry {ry}, rz {rz} rad",
               x=f"{x * 1000 + 0.0:.1f}", y=f"{y * 1000 + 0.0:.1f}", z=f"{z * 1000 + 0.0:.1f}",
               rx=f"{round(rx, 3) + 0.0:.3f}", ry=f"{round(ry, 3) + 0.0:.3f}", rz=f"{round(rz, 3) + 0.0:.3f}")


def describe(step: Step) -> Said:
    """A step for the log and the run state: `pose x 412.3, y -120.0, z 230.5 mm` or `gripper close`."""
    if step.kind == POSE:
        x, y, z = (float(v) * 1000 + 0.0 for v in step.pose[:3])
        return say("routines.step_pose", "pose x {x}, y {y}, z {z} mm", x=f"{x:.1f}", y=f"{y:.1f}", z=f"{z:.1f}")
    return say("routines.step_action", "{tool} {action}", tool=step.tool, action=step.action)


def check_group(config: RoutinesConfig, group: str) -> None:
    if not group:
        raise RoutineError(say("routines.group_needed", "a routine needs a motion group (routines.groups: {groups})",
                               groups=config.group_names()))
    if group not in config.groups:
        raise RoutineError(say("routines.group_unknown", "unknown motion group {group} for routines (routines.groups: "
                               "{groups})", group=_shown(group), groups=config.group_names()))


def check_tool_action(config: RoutinesConfig, tool: str, action: str, group: str = "") -> None:
    """The tool may be used (by a routine of `group`, when given: a tool of that group) and has the action."""
    if not tool:
        raise RoutineError(say("routines.tool_needed", "a tool action needs a tool (routines.tools: {tools})",
                               tools=config.tool_names(group)))
    check_tool(config, tool, group)
    actions = config.tools[tool]
    if action not in actions:
        raise RoutineError(say("routines.action_unknown", "unknown action {action} for tool {tool} (it has: {actions})",
                               action=_shown(action), tool=tool, actions=", ".join(actions) or "none"))


def check_tool(config: RoutinesConfig, tool: str, group: str) -> None:
    """The tool is offered for routines and, when a group is given, on that group."""
    if tool not in config.tools:
        raise RoutineError(say("routines.tool_unknown", "unknown tool {tool} for routines (routines.tools: {tools})",
                               tool=_shown(tool), tools=config.tool_names()))
    own = config.tool_groups.get(tool)
    if group and own and own != group:
        raise RoutineError(say("routines.tool_other_group", "tool {tool} is on group {own}, not {group} (a routine "
                               "uses its group's tools: {tools})", tool=tool, own=own, group=group,
                               tools=config.tool_names(group)))


def _step_shape(step: Step, group_joints: Optional[int]) -> Step:
    """The step's own form (kind, numbers), normalised: a pose keeps pose and joints, an action tool and action."""
    if step.kind == POSE:
        if len(step.pose) != 6 or not _finite(step.pose):
            if not _finite(step.pose):
                raise RoutineError(say("routines.pose_not_finite", "a pose needs 6 finite numbers (x, y, z in m, rx, "
                                       "ry, rz in rad), got {count} values (not all finite)", count=len(step.pose)))
            raise RoutineError(say("routines.pose_numbers", "a pose needs 6 finite numbers (x, y, z in m, rx, ry, rz "
                                   "in rad), got {count} values", count=len(step.pose)))
        if step.joints and not _finite(step.joints):
            raise RoutineError(say("routines.joints_not_finite", "joints must be finite numbers (rad)"))
        if step.joints and group_joints is not None and len(step.joints) != group_joints:
            raise RoutineError(say("routines.joints_count", "joints must be empty or the group's {joints} joint "
                                   "positions, got {count} values", joints=group_joints, count=len(step.joints)))
        return Step(POSE, tuple(float(v) for v in step.pose), tuple(float(v) for v in step.joints))
    if step.kind == ACTION:
        if not isinstance(step.tool, str) or not isinstance(step.action, str) or not step.action:
            raise RoutineError(say("routines.action_needed", "an action step needs an action (one of the tool's actions)"))
        return Step(ACTION, tool=step.tool, action=step.action)
    raise RoutineError(step_kind_problem(str(step.kind)))


def step_kind_problem(kind: str) -> Said:
    return say("routines.step_kind", "unknown step kind {kind} (pose or action)", kind=_shown(kind))


def checked(config: RoutinesConfig, name: str, group: str, tool: str, steps: Sequence[Step]) -> Routine:
    """The routine as it is saved (action steps carry their tool), or RoutineError saying what is wrong."""
    check_name(name)
    check_group(config, group)
    if tool:
        check_tool(config, tool, group)
    if not steps:
        raise RoutineError(say("routines.steps_needed", "a routine needs at least one step"))
    if len(steps) > MAX_STEPS:
        raise RoutineError(say("routines.steps_too_many", "too many steps ({count}, at most {max})", count=len(steps),
                               max=MAX_STEPS))
    out = []
    for i, step in enumerate(steps, 1):
        try:
            s = _step_shape(step, config.groups[group])
            if s.kind == ACTION:
                s = Step(ACTION, tool=s.tool or tool, action=s.action)
                check_tool_action(config, s.tool, s.action, group)
        except RoutineError as e:
            raise RoutineError(say("routines.step_problem", "step {step}: {why}", step=i, why=said_of(e))) from None
        out.append(s)
    return Routine(name, group, tool, tuple(out))


def runnable_problem(config: RoutinesConfig, routine: Routine) -> str:
    """Why a routine read from its file cannot run with this cell file ("" when it can)."""
    try:
        checked(config, routine.name, routine.group, routine.tool, routine.steps)
    except RoutineError as e:
        return say("routines.not_runnable", "cannot run with this cell file: {why}", why=said_of(e))
    return ""


# ================================================================ the file format
def encode(routine: Routine) -> bytes:
    """The file's content: the name is the file's name, not repeated inside (one source of truth on rename)."""
    steps: list[dict[str, Any]] = []
    for s in routine.steps:
        if s.kind == POSE:
            steps.append({"kind": POSE, "pose": list(s.pose), "joints": list(s.joints)})
        else:
            steps.append({"kind": ACTION, "tool": s.tool, "action": s.action})
    doc = {"version": FORMAT_VERSION, "group": routine.group, "tool": routine.tool, "steps": steps}
    return (json.dumps(doc, indent=2, allow_nan=False) + "\n").encode("utf-8")


def decode(name: str, data: bytes, modified: float = 0.0) -> Routine:
    """A routine from its file's bytes; RoutineError says what is wrong with the file (not with the cell)."""
    try:
        doc = json.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise RoutineError(say("routines.file_not_utf8", "the file is not UTF-8 text")) from None
    except json.JSONDecodeError as e:
        raise RoutineError(say("routines.file_not_json", "the file is not valid JSON ({why} at line {line}, column "
                               "{column})", why=e.msg, line=e.lineno, column=e.colno)) from None
    if not isinstance(doc, dict):
        raise RoutineError(say("routines.file_not_object", "the file is not a routine (expected a JSON object)"))
    if doc.get("version") != FORMAT_VERSION:
        raise RoutineError(say("routines.file_version", "unsupported routine file version {version} (this node reads "
                               "{supported})", version=repr(doc.get("version")), supported=FORMAT_VERSION))
    group, tool, raw_steps = doc.get("group"), doc.get("tool", ""), doc.get("steps")
    if not isinstance(group, str) or not isinstance(tool, str):
        raise RoutineError(say("routines.file_group_tool", "the file's group and tool must be text"))
    if not isinstance(raw_steps, list):
        raise RoutineError(say("routines.file_no_steps", "the file has no list of steps"))
    steps: list[Step] = []
    for i, raw in enumerate(raw_steps, 1):
        if not isinstance(raw, dict):
            raise RoutineError(say("routines.file_step_not_object", "step {step} in the file is not an object", step=i))
        pose, joints = raw.get("pose", []), raw.get("joints", [])
        s_tool, action = raw.get("tool", ""), raw.get("action", "")
        if not isinstance(pose, list) or not isinstance(joints, list) or not isinstance(s_tool, str) \
                or not isinstance(action, str) or not isinstance(raw.get("kind"), str):
            raise RoutineError(say("routines.file_step_types", "step {step} in the file has fields of the wrong type",
                                   step=i))
        try:
            steps.append(_step_shape(Step(raw["kind"], tuple(pose), tuple(joints), s_tool, action), None))
        except RoutineError as e:
            raise RoutineError(say("routines.file_step", "step {step} in the file: {why}", step=i, why=said_of(e))) from None
    return Routine(name, group, tool, tuple(steps), modified)
