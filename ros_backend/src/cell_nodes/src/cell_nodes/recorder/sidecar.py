"""The JSON file beside each recording (`<stem>.json`): what the Recordings page lists and draws (why, when, how
long, the topics, the timeline) without an MCAP reader in the BFF. Written atomically after the MCAP file: a
recording without one is still listed, by its file name, size and time."""
from __future__ import annotations

import json
import os
import tempfile
from typing import Any, Dict, Iterable, List, Mapping

from .mcap_file import SUFFIX, TEMP_PREFIX
from .ring import RawMessage
from .timeline import LANES, Change

SIDECAR_SUFFIX = ".json"
VERSION = 1


def sidecar_path(mcap_path: str) -> str:
    base = mcap_path[:-len(SUFFIX)] if mcap_path.endswith(SUFFIX) else mcap_path
    return base + SIDECAR_SUFFIX


def topic_counts(messages: Iterable[RawMessage]) -> List[Dict[str, Any]]:
    counts: Dict[tuple, int] = {}
    for m in messages:
        key = (m.topic, m.schema.datatype)
        counts[key] = counts.get(key, 0) + 1
    return [{"topic": t, "type": d, "count": n} for (t, d), n in sorted(counts.items())]


def describe(name: str, reason: str, at_ns: int, start_ns: int, end_ns: int, size: int,
             messages: List[RawMessage], alarms: List[str], lanes: Mapping[str, List[Change]]) -> Dict[str, Any]:
    ms = lambda t: round(t / 1e6, 3)  # noqa: E731  (ns since epoch do not fit a JSON number exactly; ms do)
    return {
        "version": VERSION, "name": name, "reason": reason, "at_ms": ms(at_ns), "start_ms": ms(start_ns),
        "end_ms": ms(end_ns), "duration_s": round((end_ns - start_ns) / 1e9, 3), "size": size,
        "messages": len(messages), "alarms": list(alarms), "topics": topic_counts(messages),
        "timeline": {"lanes": [{"id": lane, "title": title,
                                "changes": [{"t_ms": ms(c.t_ns), "text": c.text} for c in lanes.get(lane, [])]}
                               for lane, title in LANES]},
    }


def write_sidecar(path: str, data: Mapping[str, Any]) -> None:
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=SIDECAR_SUFFIX, dir=directory)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(data, f, ensure_ascii=False, separators=(",", ":"))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
