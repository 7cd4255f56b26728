"""The parameters CSV on disk: reading it against the definitions (never failing: every problem becomes a message
and the default is used) and writing it atomically after a backup.

Format (UTF-8, `\\n` line ends, quoted by Python's csv module where needed):

    id,value,unit,category,label
    approach_height,50,mm,Motion,Approach height
    recipe_name,"Bracket, left",,Process,Recipe name

Only `id` and `value` are read (by header name, in any column order; a UTF-8 BOM from a spreadsheet is fine); the
other columns are written for people who open the file in a spreadsheet, and the cell file stays the definition.
"""
from __future__ import annotations

import csv
import io
import os
import stat
import tempfile
from dataclasses import dataclass, field
from typing import Mapping, Sequence

from ..said import say
from .values import InvalidValue, ParamDef, canonical, show_value

COLUMNS = ("id", "value", "unit", "category", "label")
MAX_FILE_BYTES = 1 << 20   # a parameters file is small; a bigger one is not read into memory
BACKUPS = 3                # <csv>.bak (before the last save), <csv>.bak.1, <csv>.bak.2


@dataclass
class LoadResult:
    texts: dict[str, str]                               # every defined id -> the text in use (the default if need be)
    problems: list[str] = field(default_factory=list)   # for the operator and the log
    missing: bool = False                               # the file does not exist


def _unreadable(name: str, why: str) -> str:
    return say("parameters.file_unreadable", "cannot read {file}: {why}; every default used", file=name, why=why)


def read_csv(path: str, defs: Sequence[ParamDef], name: str) -> LoadResult:
    """Read `path` (`name` is how messages call it); never raises for what is in or around the file."""
    result = LoadResult({d.id: d.default for d in defs})
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        result.missing = True
        result.problems.append(say("parameters.file_missing", "{file} does not exist: every default used", file=name))
        return result
    except OSError as e:
        result.problems.append(_unreadable(name, e.strerror or str(e)))
        return result
    if len(raw) > MAX_FILE_BYTES:
        result.problems.append(say("parameters.file_too_large", "{file} is larger than {max} bytes: not read; every "
                                   "default used", file=name, max=MAX_FILE_BYTES))
        return result
    try:
        rows = csv.reader(io.StringIO(raw.decode("utf-8-sig"), newline=""))
        table: list[tuple[int, list[str]]] = []
        end = 0
        for row in rows:  # numbered by the record's first line (a quoted value may span several)
            table.append((end + 1, row))
            end = rows.line_num
    except (UnicodeDecodeError, csv.Error) as e:
        result.problems.append(_unreadable(name, str(e)))
        return result
    table = [(line, row) for line, row in table if any(cell.strip() for cell in row)]  # blank lines mean nothing
    if not table:
        result.problems.append(say("parameters.file_empty", "{file} is empty: every default used", file=name))
        return result
    header = [cell.strip().lower() for cell in table[0][1]]
    if "id" not in header or "value" not in header:
        result.problems.append(say("parameters.file_no_header", "{file} has no header line with `id` and `value` "
                                   "columns: every default used", file=name))
        return result
    id_col, value_col = header.index("id"), header.index("value")
    by_id = {d.id: d for d in defs}
    first_line: dict[str, int] = {}
    for line, row in table[1:]:
        pid = row[id_col].strip() if id_col < len(row) else ""
        if not pid:
            result.problems.append(say("parameters.line_no_id", "line {line}: no id; ignored", line=line))
            continue
        defn = by_id.get(pid)
        if defn is None:
            result.problems.append(say("parameters.line_unknown", "line {line}: unknown parameter {id}; ignored",
                                       line=line, id=repr(pid)))
            continue
        if pid in first_line:
            result.problems.append(say("parameters.line_again", "line {line}: {id} again (first on line {first}); "
                                       "ignored", line=line, id=pid, first=first_line[pid]))
            continue
        first_line[pid] = line
        default = show_value(defn, defn.default)
        if value_col >= len(row):
            result.problems.append(say("parameters.line_no_value", "line {line}: {label}: no value; default {default} "
                                       "used", line=line, label=defn.label, default=default))
            continue
        try:
            result.texts[pid] = canonical(defn, row[value_col])[0]
        except InvalidValue as e:
            result.problems.append(say("parameters.line_invalid", "line {line}: {why}; default {default} used",
                                       line=line, why=e.said, default=default))
    for defn in defs:
        if defn.id not in first_line:
            result.problems.append(say("parameters.not_in_file", "{label} ({id}) is not in {file}; default {default} "
                                       "used", label=defn.label, id=defn.id, file=name,
                                       default=show_value(defn, defn.default)))
    return result


def render(defs: Sequence[ParamDef], texts: Mapping[str, str]) -> bytes:
    """The file's content: the header and one row per parameter, in the cell file's order."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(COLUMNS)
    for d in defs:
        writer.writerow((d.id, texts[d.id], d.unit, d.category, d.label))
    return out.getvalue().encode("utf-8")


def backup_names(path: str, count: int = BACKUPS) -> list[str]:
    """Newest first: <csv>.bak, <csv>.bak.1, ..."""
    return [f"{path}.bak"] + [f"{path}.bak.{i}" for i in range(1, count)]


def _write_all(fd: int, data: bytes) -> None:
    """Write every byte to fd (a seam: the tests make it fail half-way)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def _replace_atomically(path: str, data: bytes, mode: int) -> None:
    """Temp file in the same directory, fsync, rename over `path`, fsync the directory: a reader sees the old file
    or the new one, never a mix, also after a power cut."""
    directory = os.path.dirname(path) or "."
    fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp", dir=directory)
    try:
        try:
            _write_all(fd, data)
            os.fchmod(fd, mode)
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    dir_fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


def write_csv(path: str, data: bytes, backups: int = BACKUPS) -> None:
    """Back the current file up (rotating `backups` copies) and replace it atomically. Raises OSError; the file is
    then unchanged.

    Each backup is replaced atomically by a copy of the next newer one (<csv>.bak by the CSV), the oldest first, then
    the CSV by the new content: a crash or a power cut at any moment leaves each file as it was or as it should
    become, never missing (renaming the backups along would leave a gap) or torn."""
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    mode = stat.S_IMODE(st.st_mode) if st is not None else 0o644
    if st is not None and backups > 0:
        names = backup_names(path, backups)
        for older, newer in reversed(list(zip(names, [path] + names[:-1]))):
            try:
                with open(newer, "rb") as f:
                    content = f.read()
            except FileNotFoundError:
                continue
            _replace_atomically(older, content, mode)
    _replace_atomically(path, data, mode)


def remove_temp_files(path: str) -> int:
    """Remove the temp files a crash mid-save left next to `path` (and its backups); only the parameters node writes
    there. Returns how many."""
    directory = os.path.dirname(path) or "."
    prefix = f".{os.path.basename(path)}."
    removed = 0
    try:
        entries = os.listdir(directory)
    except OSError:
        return 0
    for name in entries:
        if name.startswith(prefix) and name.endswith(".tmp"):
            try:
                os.unlink(os.path.join(directory, name))
                removed += 1
            except OSError:
                pass
    return removed
