"""set_level: choose which status messages this client receives (default: error)."""
from __future__ import annotations

from typing import Any, Dict

from ..op_base import LEVELS


def set_level(client: Any, msg: Dict[str, Any]) -> None:
    level = msg.get("level")
    # Spec: "If a bad string is specified, the message is dropped."
    if isinstance(level, str) and level in LEVELS:
        client.status_level = LEVELS[level]


def ignore(client: Any, msg: Dict[str, Any]) -> None:
    return None
