"""What other nodes call at start to read the cell's parameters (the process node, for one):

    from cell_nodes.cell_file import load_cell
    from cell_nodes.parameters import read_values
    params = read_values(load_cell())          # {"approach_height": 50.0, "parts_per_cycle": 3, ...}

Read-only: it never creates or changes the file. Every parameter of the cell file is in the answer, with its
default where the CSV lacks it or holds an invalid value; `read_parameters` also says what was wrong, for the log.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Optional

from .config import csv_path, parse_parameters
from .csvfile import read_csv
from .values import Value, typed


@dataclass(frozen=True)
class Snapshot:
    values: dict[str, Value]                         # id -> int | float | bool | str
    texts: dict[str, str]                            # id -> the text as stored
    problems: list[str] = field(default_factory=list)
    path: str = ""                                   # the CSV's absolute path ("" without a parameters section)


def read_parameters(cell: Mapping[str, Any], data_dir: Optional[str] = None) -> Snapshot:
    """The values and what was wrong with the file. `data_dir`: default $DATA_DIR, else the repository's .data.
    Raises config.ConfigError only when the cell file's `parameters:` section itself is unusable."""
    config = parse_parameters(cell)
    if config is None:
        return Snapshot({}, {})
    path = csv_path(config, data_dir)
    result = read_csv(path, config.items, config.csv)
    values = {d.id: typed(d, result.texts[d.id]) for d in config.items}
    return Snapshot(values, result.texts, result.problems, path)


def read_values(cell: Mapping[str, Any], data_dir: Optional[str] = None) -> dict[str, Value]:
    """{id: typed value} for every parameter of the cell file (defaults for missing or invalid ones); {} when the
    cell file has no `parameters:` section."""
    return read_parameters(cell, data_dir).values
