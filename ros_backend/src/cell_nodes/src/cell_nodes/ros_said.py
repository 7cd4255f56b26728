"""cell_nodes.said over ROS: a text's code and parameters as message fields (diagnostic_msgs/KeyValue), and back
(the ROS layer, either generation)."""
from __future__ import annotations

from typing import Any, Sequence

from cell_msgs.msg import LogEntry
from diagnostic_msgs.msg import KeyValue

from .said import Said, coded


def key_values(text: str) -> tuple[str, list[KeyValue]]:
    """A text's code and its parameters as KeyValues ("" and none for a plain string)."""
    code, params = coded(text)
    return code, [KeyValue(key=k, value=v) for k, v in params]


def said(text: str, code: str, params: Sequence[KeyValue]) -> Said:
    return Said(text, code, [(kv.key, kv.value) for kv in params])


def log_entry(stamp: Any, level: str, text: str) -> LogEntry:
    code, params = key_values(text)
    return LogEntry(stamp=stamp, level=level, text=text, code=code, params=params)


def said_of(entry: LogEntry) -> Said:
    return said(entry.text, entry.code, entry.params)
