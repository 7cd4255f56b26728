"""The recordings directory kept within a count and a byte budget: the oldest recordings go first, the newest
always stays (even alone over the budget: it is the one someone is about to look at)."""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import List

from .mcap_file import SUFFIX, TEMP_PREFIX
from .sidecar import SIDECAR_SUFFIX, sidecar_path


@dataclass(frozen=True)
class Recording:
    name: str
    path: str
    size: int
    mtime: float


def recordings(directory: str) -> List[Recording]:
    """The finished recordings, oldest first (temp files of a save in progress or cut by a power loss are not)."""
    out = []
    try:
        entries = list(os.scandir(directory))
    except FileNotFoundError:
        return []
    for e in entries:
        if not e.name.endswith(SUFFIX) or e.name.startswith(TEMP_PREFIX) or not e.is_file(follow_symlinks=False):
            continue
        st = e.stat(follow_symlinks=False)
        out.append(Recording(e.name, e.path, st.st_size, st.st_mtime))
    return sorted(out, key=lambda r: (r.mtime, r.name))


def prune(directory: str, max_count: int, max_bytes: int) -> List[str]:
    """Delete the oldest recordings until at most max_count remain and they total at most max_bytes (the newest
    stays), each with its JSON description. Leftover temp files are removed too. Returns the names deleted."""
    for e in list(os.scandir(directory)) if os.path.isdir(directory) else []:
        if e.name.startswith(TEMP_PREFIX) and e.name.endswith((SUFFIX, SIDECAR_SUFFIX)):
            try:
                os.unlink(e.path)
            except OSError:
                pass
    recs = recordings(directory)
    deleted = []
    total = sum(r.size for r in recs)
    while len(recs) > 1 and (len(recs) > max_count or total > max_bytes):
        oldest = recs.pop(0)
        for p in (oldest.path, sidecar_path(oldest.path)):
            try:
                os.unlink(p)
            except FileNotFoundError:
                pass
        total -= oldest.size
        deleted.append(oldest.name)
    return deleted
