"""The node's state: the definitions, the values in use, what was wrong with the file, and the all-or-nothing set.

The file stays the truth: before each get and set (and on the node's timer) the store re-reads it when its size,
mtime or inode changed, so a hand edit shows up without a restart.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Iterable, Optional, Sequence

from ..said import say
from .config import ParametersConfig
from .csvfile import BACKUPS, read_csv, remove_temp_files, render, write_csv
from .values import InvalidValue, ParamDef, Value, canonical, typed

Signature = Optional[tuple[int, int, int]]


@dataclass(frozen=True)
class Entry:
    defn: ParamDef
    text: str


@dataclass(frozen=True)
class SetResult:
    success: bool
    message: str                                      # a Said: the app says it in the user's language
    errors: tuple[tuple[str, str], ...] = ()          # (id, message: a Said) per refused field
    changed: tuple[tuple[str, str, str], ...] = ()    # (id, old text, new text) per saved change


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


LISTED = 10   # a message lists at most this many (each nests once more: a file of 1000 bad lines must stay small)


def listed(texts: Sequence[str]) -> str:
    """Texts joined with "; ", said as nested pairs so each keeps its code (the app says each in the user's language);
    past LISTED, "and N more" (the log and `errors` have them all)."""
    if len(texts) > LISTED:
        texts = [*texts[:LISTED], say("parameters.more", "and {count} more", count=len(texts) - LISTED)]
    out = texts[-1]
    for text in reversed(texts[:-1]):
        out = say("parameters.list", "{first}; {rest}", first=text, rest=out)
    return out


class ParameterStore:
    def __init__(self, config: ParametersConfig, path: str, backups: int = BACKUPS) -> None:
        self.config = config
        self.path = path
        self.name = config.csv          # how messages name the file (the absolute path stays in the log)
        self.backups = backups
        self.defs: tuple[ParamDef, ...] = config.items
        self._by_id = config.by_id()
        self.texts: dict[str, str] = {d.id: d.default for d in self.defs}
        self.problems: list[str] = []
        self._signature: Signature = None
        self._loaded = False

    # ---------------------------------------------------------------------------------------------- reading
    def _stat(self) -> Signature:
        try:
            st = os.stat(self.path)
        except OSError:
            return None
        return (st.st_ino, st.st_size, st.st_mtime_ns)

    def start(self) -> list[str]:
        """Remove the temp files of an interrupted save, load the file; a missing one is created from the defaults.
        Returns notes for the log."""
        removed = remove_temp_files(self.path)
        notes = [f"removed {_plural(removed, 'temp file')} of an interrupted save of {self.name}"] if removed else []
        return notes + self._load(creating_from="the defaults")

    def refresh(self) -> tuple[bool, list[str]]:
        """Re-read the file if it changed on disk. Returns (the values or problems changed, notes for the log)."""
        if self._loaded and self._stat() == self._signature and self._signature is not None:
            return False, []
        before = (dict(self.texts), list(self.problems))
        # Deleted while running: written again from the values in use (a restart would take the defaults).
        notes = self._load(creating_from="the values in use")
        return (dict(self.texts), list(self.problems)) != before, notes

    def _load(self, creating_from: str) -> list[str]:
        notes: list[str] = []
        signature = self._stat()
        result = read_csv(self.path, self.defs, self.name)
        if result.missing:
            texts = self.texts if self._loaded else {d.id: d.default for d in self.defs}
            try:
                write_csv(self.path, render(self.defs, texts), self.backups)
            except OSError as e:
                self.texts, self.problems = dict(texts), [say("parameters.not_created", "could not create {file}: "
                                                              "{why}; the values are not saved", file=self.name,
                                                              why=e.strerror or str(e))]
                self._signature, self._loaded = None, True
                return notes
            notes.append(f"{self.name} did not exist: created from {creating_from}")
            self.texts, self.problems = dict(texts), []
            signature = self._stat()
        else:
            self.texts, self.problems = result.texts, result.problems
        self._signature, self._loaded = signature, True
        return notes

    def entries(self) -> list[Entry]:
        return [Entry(d, self.texts[d.id]) for d in self.defs]

    def values(self) -> dict[str, Value]:
        return {d.id: typed(d, self.texts[d.id]) for d in self.defs}

    @property
    def message(self) -> str:
        """What get answers and the topic carries: what is wrong with the file, "" when nothing (the page shows a
        non-empty message as a warning)."""
        if not self.problems:
            return ""
        if len(self.problems) == 1:
            return say("parameters.file_problems_one", "{count} problem in {file}: {problems}", count=1, file=self.name,
                       problems=self.problems[0])
        return say("parameters.file_problems", "{count} problems in {file}: {problems}", count=len(self.problems),
                   file=self.name, problems=listed(self.problems))

    # ---------------------------------------------------------------------------------------------- writing
    def validate(self, changes: Sequence[tuple[str, str]]) -> tuple[dict[str, str], list[tuple[str, str]]]:
        """Every change checked, every bad one listed: ({id: canonical text}, [(id, message)])."""
        accepted: dict[str, str] = {}
        errors: list[tuple[str, str]] = []
        seen: set[str] = set()
        for pid, text in changes:
            defn = self._by_id.get(pid)
            if defn is None:
                errors.append((pid, say("parameters.unknown", "unknown parameter {id}", id=repr(pid))))
                continue
            if pid in seen:
                errors.append((pid, say("parameters.changed_twice", "{label}: changed twice in one request",
                                        label=defn.label)))
                accepted.pop(pid, None)
                continue
            seen.add(pid)
            try:
                accepted[pid] = canonical(defn, text)[0]
            except InvalidValue as e:
                errors.append((pid, e.said))
        return accepted, errors

    def set(self, changes: Iterable[tuple[str, str]]) -> SetResult:
        """All or nothing: one bad field and nothing is written. Changes equal to the value in use (`50.0` for
        `50`) are not changes. The file is backed up, then replaced atomically."""
        changes = list(changes)
        limit = max(100, 2 * len(self.defs))
        if len(changes) > limit:
            return SetResult(False, say("parameters.too_many_changes",
                                        "too many changes in one request ({count}, at most {max}); nothing saved",
                                        count=len(changes), max=limit))
        self.refresh()  # a hand edit since the last read is kept, not overwritten by stale values
        accepted, errors = self.validate(changes)
        if errors:
            said = (say("parameters.nothing_saved_one", "nothing saved: {count} invalid value: {errors}", count=1,
                        errors=errors[0][1]) if len(errors) == 1 else
                    say("parameters.nothing_saved", "nothing saved: {count} invalid values: {errors}",
                        count=len(errors), errors=listed([m for _, m in errors])))
            return SetResult(False, said, tuple(errors))
        changed = tuple((pid, self.texts[pid], text) for pid, text in accepted.items()
                        if typed(self._by_id[pid], text) != typed(self._by_id[pid], self.texts[pid]))
        if not changed:
            return SetResult(True, say("parameters.nothing_to_save", "nothing to save: no value differs from the saved one"))
        texts = dict(self.texts)
        texts.update({pid: new for pid, _, new in changed})
        try:
            write_csv(self.path, render(self.defs, texts), self.backups)
        except OSError as e:
            return SetResult(False, say("parameters.not_saved", "could not save {file}: {error}; nothing saved",
                                        file=self.name, error=e.strerror or str(e)))
        self.texts, self.problems, self._signature = texts, [], self._stat()
        return SetResult(True, say("parameters.saved_one", "saved {count} parameter", count=1) if len(changed) == 1 else
                         say("parameters.saved", "saved {count} parameters", count=len(changed)), (), changed)
