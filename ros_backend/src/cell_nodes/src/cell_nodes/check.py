"""Checks a cell file the way the ROS nodes and the simulator read it at start, without ROS:

    source scripts/ros-env.sh && python -m cell_nodes.check config/my-cell.yaml

The BFF's `npm run check-config` validates the file against the JSON Schema and then runs this. The nodes parse
their sections again and refuse more than a schema can express (a process step naming a configuration the robot
driver does not have, a parameter default outside its own range, duplicate module names, ...); such a node exits at
start and is respawned forever (the process nodes stay up and refuse every Start). Here every node's own parser
runs over the file, the same functions the nodes call in main():

- manual_node: manual.config.parse_manual, then resolve_hosts (groups[].host, UR_HOSTS, UR_HOST of the environment
  the check runs in) and plan_arms (one driver per host: the joints of one arm named alike, no joint name on two
  arms, a tool's move_named steps on its own arm)
- parameters_node: parameters.config.parse_parameters (ids, min <= max, each default within its own rules)
- process_server, process_node: process.config.parse_process after substitute_parameters, with each parameter's
  default from the cell file (the nodes take the parameters CSV's values, which the Parameters page keeps valid)
- alarms_node: alarms.config.parse_alarms (and alarm_mode_problem, a warning: the node runs on)
- modules_node: modules.config.parse_modules
- routines_node: routines.config.parse_routines (its dropped groups and tools are warnings: the node runs on)
- operation_mode_node: operation_mode.OperationMode
- manual_node's ros_control backend: each ros_control group against the URDF its arm's driver offers, where it can
  be known without ROS (a `urdf` file, or the simulated driver's): the chain's joints, the links, the configurations
  within the joint limits (manual.ros_control.check)
- the simulator (python -m sim): sim.cell_file.devices_from

A feature's nodes start only when the cell file has its section (scripts/feature-launch.js), so only the sections
present are checked; the operation mode and the sim always. Each parser stops at its first problem: one line per
section at most. Output: one line per problem, `<field path>: <problem>`, then `warning: ...` lines.
Exit code 0: no problem (warnings allowed), 1: problems, 2: the file cannot be read (or bad usage).
No rospy import here: it runs without a ROS master.
"""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Optional, Sequence

import yaml

from cell_nodes.cell_file import default_cell_path, load_cell

EXIT_OK, EXIT_PROBLEMS, EXIT_UNREADABLE = 0, 1, 2


@dataclass
class Report:
    problems: list[str] = field(default_factory=list)   # what makes a node (or the sim) refuse the file
    warnings: list[str] = field(default_factory=list)   # what a node logs and then works around


def _crash(section: str, who: str, e: Exception) -> str:
    """A parser that fails with something other than its ConfigError: the node would crash the same way."""
    return f"{section}: {who} cannot read this section ({type(e).__name__}: {e})"


def check_manual(cell: Mapping[str, Any], report: Report, environ: Optional[Mapping[str, str]] = None) -> None:
    from cell_nodes.manual.config import ConfigError, parse_manual, plan_arms, resolve_hosts
    try:
        config = parse_manual(cell.get("manual"))
        plan_arms(config, resolve_hosts(cell.get("manual"), os.environ if environ is None else environ))
    except ConfigError as e:
        report.problems.append(str(e))
    except Exception as e:  # noqa: BLE001 - the node would die of it too
        report.problems.append(_crash("manual", "the robot driver", e))


def parameter_defaults(cell: Mapping[str, Any]) -> tuple[dict[str, Any], Optional[str]]:
    """{id: typed default} of the cell's parameters, and the parameters node's problem (None: none). With a bad
    section, the raw defaults of the items that have an id: the process check then reports its own mistakes
    rather than repeating the parameters' one."""
    from cell_nodes.parameters.config import ConfigError, parse_parameters
    from cell_nodes.parameters.values import typed
    try:
        config = parse_parameters(cell)
    except Exception as e:  # noqa: BLE001 - ConfigError, or whatever would kill the node
        section = cell.get("parameters")
        items = section.get("items") if isinstance(section, Mapping) else None
        raw = {i["id"]: i.get("default") for i in items or []
               if isinstance(i, Mapping) and isinstance(i.get("id"), str)}
        return raw, str(e) if isinstance(e, ConfigError) else _crash("parameters", "the parameters node", e)
    if config is None:
        return {}, None
    return {d.id: typed(d, d.default) for d in config.items}, None


def check_parameters(cell: Mapping[str, Any], report: Report) -> None:
    problem = parameter_defaults(cell)[1]
    if problem:
        report.problems.append(problem)


def check_process(cell: Mapping[str, Any], report: Report) -> None:
    from cell_nodes.process.config import ConfigError, parse_process, substitute_parameters
    values, _ = parameter_defaults(cell)
    try:
        # What parse_cell_process does, with the defaults for the CSV's values.
        parse_process(substitute_parameters(cell.get("process"), values), cell.get("manual"))
    except ConfigError as e:
        report.problems.append(str(e))
    except Exception as e:  # noqa: BLE001
        report.problems.append(_crash("process", "the process nodes", e))


def check_alarms(cell: Mapping[str, Any], report: Report) -> None:
    from cell_nodes.alarms.config import ConfigError, alarm_mode_problem, parse_alarms
    try:
        parse_alarms(cell)
    except ConfigError as e:
        report.problems.append(str(e))
        return
    except Exception as e:  # noqa: BLE001
        report.problems.append(_crash("alarms", "the alarms node", e))
        return
    section = cell.get("alarms") or {}
    if isinstance(section, Mapping) and "alarm_mode" in section and not section["alarm_mode"]:
        return  # switched off on purpose: not worth a warning
    note = alarm_mode_problem(cell)
    if note:
        report.warnings.append(f"alarms.alarm_mode: {note}")


def check_modules(cell: Mapping[str, Any], report: Report) -> None:
    from cell_nodes.modules.config import ConfigError, parse_modules
    try:
        parse_modules(cell.get("modules"))
    except ConfigError as e:
        report.problems.append(str(e))
    except Exception as e:  # noqa: BLE001
        report.problems.append(_crash("modules", "the modules node", e))


def check_routines(cell: Mapping[str, Any], report: Report) -> None:
    from cell_nodes.routines.config import ConfigError, parse_routines
    try:
        config = parse_routines(cell)
    except ConfigError as e:
        report.problems.append(str(e))
        return
    except Exception as e:  # noqa: BLE001
        report.problems.append(_crash("routines", "the routines node", e))
        return
    report.warnings.extend(config.warnings)


def check_operation_mode(cell: Mapping[str, Any], report: Report) -> None:
    from cell_nodes.operation_mode import OperationMode
    section = cell.get("operation_mode")
    if not isinstance(section, Mapping):
        report.problems.append(f"operation_mode: the operation mode node needs this section, got {section!r}")
        return
    try:
        OperationMode(section.get("modes") or [], section.get("initial"))
    except Exception as e:  # noqa: BLE001 - ValueError naming the mode
        report.problems.append(f"operation_mode: {e}")


def check_arm_models(cell: Mapping[str, Any], report: Report, path: str) -> None:
    """ros_control groups against their URDF (a file, or the simulated driver's): joints, links, limits."""
    from cell_nodes.manual.ros_control.check import check_ros_control
    try:
        report.problems.extend(check_ros_control(cell, path))
    except Exception as e:  # noqa: BLE001
        report.problems.append(_crash("manual", "the ros_control backend", e))


def check_sim(cell: Mapping[str, Any], report: Report, path: str = "<cell file>") -> None:
    from sim.cell_file import CellFileError, devices_from
    try:
        devices_from(dict(cell), path)
    except CellFileError as e:
        text = str(e)
        prefix = f"cell file {path}: "  # its messages name the file; ours are all about that one file
        report.problems.append(text[len(prefix):] if text.startswith(prefix) else text)
    except Exception as e:  # noqa: BLE001
        report.problems.append(_crash("video/sensors", "the simulator", e))


# Section -> the check of the nodes that start when the cell file has it (ros_backend/src/cell_bringup/launch).
SECTION_CHECKS: tuple[tuple[str, Callable[[Mapping[str, Any], Report], None]], ...] = (
    ("manual", check_manual),
    ("parameters", check_parameters),
    ("process", check_process),
    ("alarms", check_alarms),
    ("modules", check_modules),
    ("routines", check_routines),
)


def check_cell(cell: Mapping[str, Any], path: str = "<cell file>") -> Report:
    """Every node's and the sim's verdict on a parsed cell file."""
    report = Report()
    check_operation_mode(cell, report)
    for section, check in SECTION_CHECKS:
        if section in cell:
            check(cell, report)
    if "manual" in cell:
        check_arm_models(cell, report, path)
    check_sim(cell, report, path)
    return report


def read_cell(path: str) -> dict[str, Any]:
    """The cell file as the nodes load it; ValueError with one readable line when it cannot be read."""
    try:
        return load_cell(path)
    except yaml.YAMLError as e:
        raise ValueError(f"{path}: not valid YAML: {' '.join(str(e).split())}") from None
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror or e}") from None
    except ValueError as e:  # not a mapping ("<path>: not a cell file"), bad UTF-8
        text = str(e)
        raise ValueError(text if text.startswith(f"{path}: ") else f"{path}: cannot read: {text}") from None


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) > 1 or any(a.startswith("-") for a in args):
        print("usage: python -m cell_nodes.check [cell.yaml]   (default: $CELL_CONFIG, else the demo cell)",
              file=sys.stderr)
        return EXIT_UNREADABLE
    path = args[0] if args else default_cell_path()
    try:
        cell = read_cell(path)
    except ValueError as e:
        print(e)
        return EXIT_UNREADABLE
    report = check_cell(cell, path)
    for line in report.problems:
        print(line)
    for line in report.warnings:
        print(f"warning: {line}")
    return EXIT_PROBLEMS if report.problems else EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
