"""Small state files that a node keeps across its own restart and a power cut: `$DATA_DIR/state/<name>.json`.

- Writes are atomic: a temp file in the same directory, fsync, rename over the old file, fsync of the directory. A
  power cut leaves the old file or the new one, never a torn one (a leftover temp file is removed at the next load).
- Reading never raises: no file is "nothing saved"; a file that cannot be read, is not ours, has another version or
  fails the feature's own check is a problem the node logs before it starts clean. Such a file is moved aside to
  `<name>.json.bad` (the evidence stays, the next start is clean, the next save writes a good file).
- Where: the node's `~state_dir` parameter, else `$DATA_DIR/state`. With neither (a node started by hand, or by a test
  that gives it no DATA_DIR) there is no file: the state lives in memory only, which the node says in its log.

No ROS here: the features' cores say what to keep and check what they get back.
"""
from __future__ import annotations

import json
import math
import os
import tempfile
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Optional

STATE_SUBDIR = "state"
SUFFIX = ".json"
BAD_SUFFIX = ".bad"
TEMP_PREFIX = ".tmp-"
MAX_BYTES = 64 * 1024      # these files hold a few fields: anything bigger is not ours


def state_dir(explicit: Optional[str] = None, environ: Mapping[str, str] = os.environ) -> Optional[str]:
    """The directory for state files: `explicit` (a node's ~state_dir), else $DATA_DIR/state, else None."""
    if explicit:
        return os.path.abspath(explicit)
    data_dir = environ.get("DATA_DIR")
    return os.path.join(os.path.abspath(data_dir), STATE_SUBDIR) if data_dir else None


def finite_number(value: Any, minimum: float = 0.0) -> bool:
    """A JSON number (not a bool), finite and at least `minimum`: what the features' checks accept for times."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            and value >= minimum)


@dataclass(frozen=True)
class Loaded:
    data: Optional[dict[str, Any]] = None   # None: nothing saved, or the file was not usable
    saved_at: float = 0.0                   # when it was written (seconds since the epoch), 0 unknown
    problem: str = ""                       # why the file was not used, for the node's log ("" none)


class StateFile:
    """One feature's state file. `kind` names what the file holds ("alarms.mode"): a file of another kind or
    version is refused, never half-used."""

    def __init__(self, directory: Optional[str], name: str, kind: str, version: int = 1) -> None:
        self.directory = os.path.abspath(directory) if directory else None
        self.name = name
        self.kind = kind
        self.version = version

    @property
    def path(self) -> Optional[str]:
        return os.path.join(self.directory, self.name + SUFFIX) if self.directory else None

    # ---------------------------------------------------------------- reading
    def load(self, check: Callable[[dict[str, Any]], Optional[str]] = lambda data: None) -> Loaded:
        """The saved data, or why there is none. `check(data)` returns what is wrong with the data for this cell
        (a mode the cell file no longer lists), or None."""
        path = self.path
        if path is None:
            return Loaded()
        self._remove_temp_files()
        try:
            with open(path, "rb") as f:
                raw = f.read(MAX_BYTES + 1)
        except FileNotFoundError:
            return Loaded()
        except OSError as e:
            # Not moved aside: the file may be fine and only unreadable now (permissions); the next save replaces it.
            return Loaded(problem=f"cannot read {path}: {e.strerror or e}; starting clean")
        why, doc = self._decode(raw)
        if why is None:
            why = check(doc["data"])
        if why is not None:
            return Loaded(problem=f"{path}: {why}; starting clean{self._move_aside(path)}")
        saved_at = doc.get("saved_at")
        return Loaded(doc["data"], float(saved_at) if finite_number(saved_at) else 0.0)

    def _decode(self, raw: bytes) -> tuple[Optional[str], dict[str, Any]]:
        if len(raw) > MAX_BYTES:
            return f"larger than {MAX_BYTES} bytes: not a state file", {}
        try:
            doc = json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            return f"not valid JSON ({e})", {}
        if not isinstance(doc, dict):
            return "not a JSON object", {}
        if doc.get("kind") != self.kind:
            return f"holds {doc.get('kind')!r}, not {self.kind!r}", {}
        if doc.get("version") != self.version:
            return f"version {doc.get('version')!r}, this node reads version {self.version}", {}
        if not isinstance(doc.get("data"), dict):
            return "no `data` object", {}
        return None, doc

    def _move_aside(self, path: str) -> str:
        try:
            os.replace(path, path + BAD_SUFFIX)
            return f" (the file was moved to {path + BAD_SUFFIX})"
        except OSError as e:
            return f" (could not move it aside: {e.strerror or e})"

    def _remove_temp_files(self) -> None:
        """Temp files of this state file left by a crash mid-save."""
        assert self.directory is not None
        prefix = f"{TEMP_PREFIX}{self.name}-"
        try:
            entries = os.listdir(self.directory)
        except OSError:
            return
        for entry in entries:
            if entry.startswith(prefix):
                try:
                    os.unlink(os.path.join(self.directory, entry))
                except OSError:
                    pass

    # ---------------------------------------------------------------- writing
    def save(self, data: Mapping[str, Any], now: Optional[float] = None) -> None:
        """Replace the file atomically. Raises OSError (the old file is then unchanged) or ValueError (data that
        JSON cannot hold, e.g. NaN). Without a directory: nothing to do."""
        if self.directory is None:
            return
        doc = {"kind": self.kind, "version": self.version, "saved_at": time.time() if now is None else now,
               "data": dict(data)}
        body = (json.dumps(doc, indent=1, sort_keys=True, allow_nan=False) + "\n").encode("utf-8")
        os.makedirs(self.directory, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{self.name}-", suffix=SUFFIX, dir=self.directory)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(body)
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp, 0o644)   # mkstemp's 0600 would hide it from the admin's backups
            os.replace(tmp, self.path)
            self._sync_directory()
        finally:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass

    def _sync_directory(self) -> None:
        """Make the rename itself durable (a power cut right after must not bring the old file back)."""
        assert self.directory is not None
        fd: Optional[int] = None
        try:
            fd = os.open(self.directory, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
            os.fsync(fd)
        except OSError:
            pass  # some file systems cannot fsync a directory; the data itself is synced
        finally:
            if fd is not None:
                os.close(fd)


class Saver:
    """Writes a feature's state file whenever its data changed since the last write. `update(snapshot)` takes the
    snapshot under its own lock, so concurrent callers never write an older state over a newer one. A failed write
    is reported once per distinct reason (`on_error`) and tried again on the next update."""

    def __init__(self, file: StateFile, saved: Optional[Mapping[str, Any]] = None,
                 on_error: Callable[[str], None] = lambda message: None) -> None:
        self.file = file
        self.on_error = on_error
        self._saved: Optional[dict[str, Any]] = dict(saved) if saved is not None else None
        self._lock = threading.Lock()
        self._last_error = ""

    def update(self, snapshot: Callable[[], Mapping[str, Any]]) -> bool:
        """Save what `snapshot()` returns if it differs from the file; True when written."""
        if self.file.directory is None:
            return False
        with self._lock:
            data = dict(snapshot())
            if data == self._saved:
                return False
            try:
                self.file.save(data)
            except (OSError, ValueError) as e:
                why = f"could not save {self.file.path}: {getattr(e, 'strerror', None) or e}"
                if why != self._last_error:
                    self._last_error = why
                    self.on_error(why)
                return False
            self._saved, self._last_error = data, ""
            return True
