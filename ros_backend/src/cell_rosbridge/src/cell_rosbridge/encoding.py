"""Envelope encodings: JSON text frames, CBOR binary frames, PNG compression and fragmentation."""
from __future__ import annotations

import base64
import json
import math
import struct
import zlib
from typing import Any, Dict, List, Union

import cbor2

Frame = Union[str, bytes]  # str = text frame, bytes = binary frame


class DecodeError(ValueError):
    pass


def encode_json(obj: Dict[str, Any]) -> str:
    # Compact separators: smaller frames. ensure_ascii stays on: the C encoder's ASCII path is ~2x faster
    # on large strings (base64 image data), and \u escapes are valid JSON for any client.
    return json.dumps(obj, separators=(",", ":"))


def encode_cbor(obj: Dict[str, Any]) -> bytes:
    return cbor2.dumps(obj)


def decode_frame(frame: Frame) -> Any:
    """Parse a client frame: text is JSON, binary is CBOR (rosbridge accepts both)."""
    try:
        if isinstance(frame, (bytes, bytearray, memoryview)):
            return cbor2.loads(bytes(frame))
        return json.loads(frame)
    except Exception as exc:  # json and cbor2 raise many kinds on bad input
        raise DecodeError(f"cannot parse {'CBOR' if isinstance(frame, (bytes, bytearray)) else 'JSON'}: "
                          f"{str(exc)[:200]}") from exc


def fragment(text: str, frag_id: str, fragment_size: int) -> List[str]:
    """Split an encoded JSON message into `fragment` ops whose data parts are at most fragment_size chars."""
    size = max(1, int(fragment_size))
    parts = [text[i:i + size] for i in range(0, len(text), size)]
    total = len(parts)
    return [encode_json({"op": "fragment", "id": frag_id, "data": p, "num": n, "total": total})
            for n, p in enumerate(parts)]


def png_encode(text: str) -> str:
    """rosbridge 'png' compression: the JSON bytes as the RGB pixels of a square image, base64 encoded.

    Padding is '\n' (JSON whitespace) so the decoded pixel string still parses.
    """
    data = text.encode("utf-8")
    width = int(math.sqrt(len(data) / 3.0)) + 1
    data += b"\n" * (width * width * 3 - len(data))
    stride = width * 3
    raw = b"".join(b"\x00" + data[y * stride:(y + 1) * stride] for y in range(width))

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, width, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    return base64.b64encode(png).decode("ascii")


def png_decode(b64: str) -> str:
    """Inverse of png_encode (used by tests and for symmetric tooling)."""
    png = base64.b64decode(b64)
    pos, idat, width = 8, b"", 0
    while pos < len(png):
        (length,) = struct.unpack(">I", png[pos:pos + 4])
        kind, body = png[pos + 4:pos + 8], png[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width = struct.unpack(">I", body[:4])[0]
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * 3
    rows = [raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)] for y in range(width)]
    return b"".join(rows).decode("utf-8").rstrip("\n")


def json_frames(text: str, compression: str, fragment_size: int, frag_id: str) -> List[Frame]:
    """Frames for an encoded JSON message: as is, png-compressed, and/or fragmented."""
    if compression == "png":
        png = png_encode(text)
        if fragment_size and len(png) > fragment_size:
            parts = [png[i:i + fragment_size] for i in range(0, len(png), fragment_size)]
            return [encode_json({"op": "png", "id": frag_id, "data": p, "num": n, "total": len(parts)})
                    for n, p in enumerate(parts)]
        return [encode_json({"op": "png", "data": png})]
    if fragment_size and len(text) > fragment_size:
        return fragment(text, frag_id, fragment_size)
    return [text]
