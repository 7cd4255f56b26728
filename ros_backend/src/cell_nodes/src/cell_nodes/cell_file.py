"""Reads the cell file for the ROS nodes (the BFF validates it against the JSON Schema at start)."""
from __future__ import annotations

import os
from typing import Any

import yaml


def default_cell_path() -> str:
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 5))
    return os.environ.get("CELL_CONFIG") or os.path.join(root, "config", "demo-cell.yaml")


def load_cell(path: str | None = None) -> dict[str, Any]:
    with open(path or default_cell_path(), encoding="utf-8") as f:
        doc = yaml.safe_load(f)
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: not a cell file")
    return doc

