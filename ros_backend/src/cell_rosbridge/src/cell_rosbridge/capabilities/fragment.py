"""fragment (client -> server): reassemble a message split into fragment ops, then dispatch it."""
from __future__ import annotations

from typing import Any, Dict

from ..op_base import ProtocolError, require

MAX_FRAGMENTS = 100_000


def fragment(client: Any, msg: Dict[str, Any]) -> None:
    frag_id = msg.get("id")
    if frag_id is None or isinstance(frag_id, (bool, dict, list)):
        raise ProtocolError("missing field 'id'")
    data = require(msg, "data", str)
    num = require(msg, "num", int)
    total = require(msg, "total", int)
    if not 0 < total <= MAX_FRAGMENTS or not 0 <= num < total:
        raise ProtocolError(f"bad fragment numbering num={num} total={total}")
    cfg = client.context.config
    buffers = client.fragments
    buf = buffers.get(frag_id)
    if buf is None or buf["total"] != total:
        if len(buffers) >= cfg.max_fragment_buffers:  # bound memory: forget the oldest incomplete one
            buffers.pop(next(iter(buffers)))
        buf = buffers[frag_id] = {"total": total, "parts": {}, "size": 0}
    if num not in buf["parts"]:
        buf["size"] += len(data)
    buf["parts"][num] = data
    if buf["size"] > cfg.max_message_size:
        del buffers[frag_id]
        raise ProtocolError(f"reassembled message exceeds max_message_size {cfg.max_message_size}")
    if len(buf["parts"]) == total:
        del buffers[frag_id]
        client.incoming("".join(buf["parts"][i] for i in range(total)))
