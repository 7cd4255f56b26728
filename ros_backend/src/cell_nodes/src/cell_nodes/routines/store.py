"""The routine files: one `<name>.json` per routine in one directory. Names are checked before they become a path
(model.check_name: no separators, no leading dot), writes are atomic (temp file, fsync, rename, directory fsync),
and a file that cannot be read is reported in the list with why, never fatal. Not thread-safe by itself: the
Routines facade serialises the calls."""
from __future__ import annotations

import errno
import os
import tempfile
from typing import Optional

from ..said import Said, say
from .model import Routine, RoutineError, check_name, decode, encode, name_problem, said_of

SUFFIX = ".json"
TEMP_PREFIX = ".tmp-"          # a leading dot: never a routine name, so never listed
MAX_FILE_BYTES = 4 * 1024 * 1024


def _why(e: OSError) -> str:
    return e.strerror or str(e)


def no_such(name: str) -> Said:
    return say("routines.no_such", "no routine named {name}", name=repr(name))


def exists(name: str) -> Said:
    return say("routines.exists", "a routine named {name} exists already", name=repr(name))


class RoutineStore:
    def __init__(self, directory: str) -> None:
        self.directory = os.path.abspath(directory)

    # ---------------------------------------------------------------- paths
    def path(self, name: str) -> str:
        check_name(name)
        path = os.path.join(self.directory, name + SUFFIX)
        # check_name already keeps the name to one path component; this guards the guard.
        if os.path.dirname(path) != self.directory:
            raise RoutineError(say("routines.name_invalid", "invalid routine name {name}", name=repr(name)))
        return path

    def _names(self) -> list[str]:
        try:
            entries = os.listdir(self.directory)
        except FileNotFoundError:
            return []
        except OSError as e:
            raise RoutineError(say("routines.cannot_read_directory", "cannot read the routines directory {directory}: "
                                   "{why}", directory=self.directory, why=_why(e))) from None
        # Other files (temp files, hidden files, names we would refuse) are not routines.
        return [f[:-len(SUFFIX)] for f in entries if f.endswith(SUFFIX) and name_problem(f[:-len(SUFFIX)]) is None]

    # ---------------------------------------------------------------- reading
    def list(self) -> list[Routine]:
        """Every routine, sorted by name (case-insensitively, then exactly); unreadable ones carry their error."""
        out = []
        for name in sorted(self._names(), key=lambda n: (n.casefold(), n)):
            try:
                out.append(self.read(name))
            except RoutineError:
                if os.path.lexists(self.path(name)):  # a dangling link; a file deleted meanwhile is simply gone
                    out.append(Routine(name, error=say("routines.file_dangling", "{file} is a link to nothing",
                                                       file=name + SUFFIX)))
        return out

    def read(self, name: str) -> Routine:
        """The routine as its file says; a file that cannot be read gives a Routine with `error` set."""
        path = self.path(name)
        try:
            st = os.stat(path)
            if not os.path.isfile(path):
                return Routine(name, modified=st.st_mtime, error=say("routines.file_not_regular",
                                                                     "{file} is not a regular file", file=name + SUFFIX))
            if st.st_size > MAX_FILE_BYTES:
                return Routine(name, modified=st.st_mtime,
                               error=say("routines.file_too_large", "{file} is too large ({size} bytes, at most {max})",
                                         file=name + SUFFIX, size=st.st_size, max=MAX_FILE_BYTES))
            with open(path, "rb") as f:
                data = f.read(MAX_FILE_BYTES + 1)
        except FileNotFoundError:
            raise RoutineError(no_such(name)) from None
        except OSError as e:
            return Routine(name, error=say("routines.file_unreadable", "cannot read {file}: {why}", file=name + SUFFIX,
                                           why=_why(e)))
        try:
            return decode(name, data, st.st_mtime)
        except RoutineError as e:
            return Routine(name, modified=st.st_mtime, error=say("routines.file_problem", "{file}: {why}",
                                                                 file=name + SUFFIX, why=said_of(e)))

    # ---------------------------------------------------------------- writing
    def save(self, routine: Routine, overwrite: bool) -> bool:
        """Write atomically; returns whether a routine of that name was replaced. Without `overwrite` an existing
        routine is never replaced, also not by a file that appeared meanwhile (hard link, not rename)."""
        final = self.path(routine.name)
        replaced = os.path.lexists(final)
        if replaced and not overwrite:
            raise RoutineError(exists(routine.name))
        try:
            os.makedirs(self.directory, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=SUFFIX, dir=self.directory)
        except OSError as e:
            raise RoutineError(say("routines.cannot_write_directory", "cannot write in the routines directory "
                                   "{directory}: {why}", directory=self.directory, why=_why(e))) from None
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(encode(routine))
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp, 0o644)   # mkstemp's 0600 would hide routines from the admin's backups
            if overwrite:
                os.replace(tmp, final)
            else:
                self._link_new(tmp, final, routine.name)
            self._sync_directory()
        except OSError as e:
            raise RoutineError(say("routines.cannot_save", "cannot save routine {name}: {why}", name=repr(routine.name),
                                   why=_why(e))) from None
        finally:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
        return replaced

    def rename(self, name: str, new_name: str) -> None:
        src, dst = self.path(name), self.path(new_name)
        if not os.path.lexists(src):
            raise RoutineError(no_such(name))
        if name == new_name:
            raise RoutineError(say("routines.same_name", "routine {name} has that name already", name=repr(name)))
        try:
            if self._link_new(src, dst, new_name):
                os.unlink(src)
            self._sync_directory()
        except OSError as e:
            raise RoutineError(say("routines.cannot_rename", "cannot rename routine {name}: {why}", name=repr(name),
                                   why=_why(e))) from None

    def delete(self, name: str) -> None:
        try:
            os.unlink(self.path(name))
            self._sync_directory()
        except FileNotFoundError:
            raise RoutineError(no_such(name)) from None
        except OSError as e:
            raise RoutineError(say("routines.cannot_delete", "cannot delete routine {name}: {why}", name=repr(name),
                                   why=_why(e))) from None

    def remove_temp_files(self) -> int:
        """Temp files left by a crash mid-save (only this node writes here)."""
        removed = 0
        try:
            entries = os.listdir(self.directory)
        except OSError:
            return 0
        for f in entries:
            if f.startswith(TEMP_PREFIX):
                try:
                    os.unlink(os.path.join(self.directory, f))
                    removed += 1
                except OSError:
                    pass
        return removed

    # ---------------------------------------------------------------- helpers
    @staticmethod
    def _link_new(src: str, dst: str, dst_name: str) -> bool:
        """Give `src` the name `dst` only if `dst` does not exist (atomically, with a hard link). True: linked (`src`
        is still there); False: renamed (a file system without hard links)."""
        try:
            os.link(src, dst, follow_symlinks=False)
            return True
        except FileExistsError:
            raise RoutineError(exists(dst_name)) from None
        except OSError as e:
            if e.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK):
                raise
            # A file system without hard links: check, then rename (the facade's lock keeps our own writers out).
            if os.path.lexists(dst):
                raise RoutineError(exists(dst_name)) from None
            os.rename(src, dst)
            return False

    def _sync_directory(self) -> None:
        """Make the rename itself durable (a power cut right after must not bring the old file back)."""
        fd: Optional[int] = None
        try:
            fd = os.open(self.directory, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
            os.fsync(fd)
        except OSError:
            pass  # some file systems cannot fsync a directory; the data itself is synced
        finally:
            if fd is not None:
                os.close(fd)
