"""Parameters (feature `parameters`): the cell's typed parameters, defined in the cell file's `parameters:` section
and stored in a CSV under DATA_DIR that nodes read at start. Plain Python, tested without ROS.

- values: a parameter's definition and the rules for its values (text in, canonical text and typed value out, or a
  message naming the parameter)
- config: the cell file's section (definitions, the CSV's path relative to DATA_DIR), checked
- csvfile: reading the CSV (problems become messages, defaults are used) and writing it (backup, then atomic
  replace)
- store: the node's state and the all-or-nothing set
- reader: `read_values(cell)`, what other nodes call at start

The rospy node (cell_nodes/scripts/parameters_node) only wires the store to the services and the topic.
"""
from .config import ConfigError
from .reader import Snapshot, read_parameters, read_values

__all__ = ["ConfigError", "Snapshot", "read_parameters", "read_values"]
