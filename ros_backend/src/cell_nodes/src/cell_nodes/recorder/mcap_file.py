"""A window of raw ROS 1 messages as an MCAP file (profile ros1: schemas `ros1msg`, messages `ros1`), written
atomically: a temp file in the same directory, fsync, rename, fsync of the directory. Readers: Foxglove, the mcap
CLI, mcap_ros1.reader, rosbags."""
from __future__ import annotations

import os
import tempfile
from typing import Dict, Iterable, Mapping, Tuple

from mcap.writer import CompressionType, Writer

from .ring import RawMessage

PROFILE = "ros1"
SCHEMA_ENCODING = "ros1msg"
MESSAGE_ENCODING = "ros1"
TEMP_PREFIX = ".tmp-"
SUFFIX = ".mcap"


def write_mcap(path: str, messages: Iterable[RawMessage], metadata: Mapping[str, str] = {},
               library: str = "cell_nodes recorder") -> int:
    """Write the messages (oldest first) to `path`; `metadata` becomes a `recording` metadata record (why, when).
    Returns the file's size. On any error no file is left at `path` (nor a temp file)."""
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=SUFFIX, dir=directory)
    try:
        with os.fdopen(fd, "wb") as f:
            writer = Writer(f, compression=CompressionType.ZSTD)  # the mcap library depends on zstandard
            writer.start(profile=PROFILE, library=library)
            schemas: Dict[Tuple[str, str], int] = {}
            channels: Dict[Tuple[str, str], int] = {}
            sequence: Dict[int, int] = {}
            for m in messages:
                sid = schemas.get((m.schema.datatype, m.schema.md5sum))
                if sid is None:
                    sid = schemas[(m.schema.datatype, m.schema.md5sum)] = writer.register_schema(
                        name=m.schema.datatype, encoding=SCHEMA_ENCODING, data=m.schema.definition.encode())
                cid = channels.get((m.topic, m.schema.md5sum))
                if cid is None:
                    cid = channels[(m.topic, m.schema.md5sum)] = writer.register_channel(
                        topic=m.topic, message_encoding=MESSAGE_ENCODING, schema_id=sid,
                        metadata={"md5sum": m.schema.md5sum})
                sequence[cid] = sequence.get(cid, 0) + 1
                writer.add_message(channel_id=cid, log_time=m.t_ns, publish_time=m.received_ns or m.t_ns, data=m.data,
                                   sequence=sequence[cid])
            if metadata:
                writer.add_metadata("recording", {str(k): str(v) for k, v in metadata.items()})
            writer.finish()
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    _sync_directory(directory)
    return os.path.getsize(path)


def _sync_directory(directory: str) -> None:
    """Make the rename durable (a power cut right after must not lose the file)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass  # some file systems cannot fsync a directory; the data itself is synced
    finally:
        os.close(fd)
