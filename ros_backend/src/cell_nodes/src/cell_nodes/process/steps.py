"""What a step says (its text for the page and the log) and where a pose step goes in a given cycle."""
from __future__ import annotations

from typing import Mapping, Sequence

from cell_nodes.manual.frames import relative_target

from cell_nodes.said import say

from .config import MoveNamed, MovePose, MoveRelative, Routine, Step, Tool, WaitTime, WaitTopic

AXES = ("x", "y", "z", "rx", "ry", "rz")
CONDITION_SIGNS = {"equals": "=", "above": ">", "below": "<"}


def table_index(cycle: int, length: int) -> int:
    """The pose-table entry (0-based) cycle `cycle` (1-based) uses: the table repeats after its last entry."""
    return (max(cycle, 1) - 1) % length


def _num(v: float) -> str:
    return f"{round(v, 4):g}"


def _value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return _num(v)
    return str(v)


def describe(step: Step, cycle: int, poses: Mapping[str, Sequence[Sequence[float]]]) -> str:
    """The step's text: its own `text` if the cell file gives one ({n}: the pose-table entry's number); else what it
    does, said with a code (cell_nodes.said) so the app says it in the user's language."""
    n = table_index(cycle, len(poses[step.table])) + 1 if isinstance(step, MovePose) and step.table else 0
    if step.text:  # (said with a code, so the app can say it in the cell file's text of the user's language)
        return say("process.step_text", "{text}", text=step.text.replace("{n}", str(n)) if n else step.text)
    note_text = getattr(step, "note", "")
    note: object = say("process.step_note", " ({note})", note=note_text) if note_text else ""
    if isinstance(step, MoveNamed):
        return say("process.step_move_named", "Move to {name}", name=step.name)
    if isinstance(step, MoveRelative):
        parts = ", ".join(f"{a} {v:+g}{' m' if i < 3 else ' rad'}" for i, (a, v) in enumerate(zip(AXES, step.offset)) if v)
        if step.frame == "tool":
            return say("process.step_move_relative_tool", "Move relative {offset} (tool){note}", offset=parts or "0",
                       note=note)
        return say("process.step_move_relative", "Move relative {offset}{note}", offset=parts or "0", note=note)
    if isinstance(step, MovePose):
        if step.table:
            return say("process.step_move_table", "Move to {table} {n}{note}", table=step.table, n=n, note=note)
        x, y, z = (_num(v) for v in step.pose[:3])
        return say("process.step_move_pose", "Move to pose (x {x}, y {y}, z {z}){note}", x=x, y=y, z=z, note=note)
    if isinstance(step, Tool):
        # The tool's and the action's names are the cell file's (manual.tools): as they are, in every language.
        return say("process.step_tool", "{tool} {action}", tool=f"{step.tool[:1].upper()}{step.tool[1:]}",
                   action=step.action)
    if isinstance(step, WaitTime):
        return say("process.step_wait", "Wait {seconds} s", seconds=_num(step.seconds))
    if isinstance(step, WaitTopic):
        return say("process.step_wait_topic", "Wait for {topic} {field} {sign} {value}", topic=step.topic,
                   field=step.field, sign=CONDITION_SIGNS[step.condition], value=_value(step.value))
    if isinstance(step, Routine):
        return say("process.step_routine", "Run routine {name}", name=step.name)
    raise TypeError(f"not a step: {step!r}")


def resolve_pose(step: MovePose, cycle: int, poses: Mapping[str, Sequence[Sequence[float]]]) -> list[float]:
    """The absolute TCP pose of a move_pose step in this cycle: the literal pose or the table's entry, then the
    offset in the base frame (translation along the base axes; rotation about base-parallel axes through the TCP,
    like the driver's relative moves in frame base)."""
    if step.table:
        table = poses[step.table]
        base = list(table[table_index(cycle, len(table))])
    else:
        base = list(step.pose or ())
    off = step.offset
    if not off or not any(off):
        return base
    if not any(off[3:]):  # a pure translation: keep the taught rotation vector exactly as written
        return [base[0] + off[0], base[1] + off[1], base[2] + off[2], *base[3:]]
    return relative_target(base, off, "base")
