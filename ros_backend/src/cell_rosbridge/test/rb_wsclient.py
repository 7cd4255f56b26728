"""Minimal blocking WebSocket client for tests: full control over frames (malformed, oversized, unread)."""
from __future__ import annotations

import base64
import json
import os
import socket
import struct
import time
from typing import Any, Optional, Tuple, Union

import cbor2


class WSClosed(Exception):
    pass


class WSClient:
    def __init__(self, port: int, host: str = "127.0.0.1", timeout: float = 5.0, rcvbuf: int = 0) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf:  # a small receive buffer makes a "slow client" fill up quickly
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.settimeout(timeout)
        self.sock.connect((host, port))
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           f"Sec-WebSocket-Version: 13\r\n\r\n").encode())
        self._buf = b""
        while b"\r\n\r\n" not in self._buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise WSClosed("closed during handshake")
            self._buf += chunk
        head, self._buf = self._buf.split(b"\r\n\r\n", 1)
        if b" 101 " not in head.split(b"\r\n")[0]:
            raise WSClosed(f"handshake refused: {head[:200]!r}")

    # -------------------------------------------------------------- sending
    def send_frame(self, payload: bytes, opcode: int = 1, fin: bool = True) -> None:
        header = bytes([(0x80 if fin else 0) | opcode])
        n = len(payload)
        if n < 126:
            header += bytes([0x80 | n])
        elif n < 65536:
            header += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            header += bytes([0x80 | 127]) + struct.pack(">Q", n)
        mask = os.urandom(4)
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload)) if n < 4096 else _mask_fast(payload, mask)
        self.sock.sendall(header + mask + masked)

    def send_text(self, text: str) -> None:
        self.send_frame(text.encode("utf-8"), 1)

    def send_json(self, obj: Any) -> None:
        self.send_text(json.dumps(obj))

    def send_cbor(self, obj: Any) -> None:
        self.send_frame(cbor2.dumps(obj), 2)

    # -------------------------------------------------------------- receiving
    def _read(self, n: int) -> bytes:
        while len(self._buf) < n:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise WSClosed("connection closed")
            self._buf += chunk
        out, self._buf = self._buf[:n], self._buf[n:]
        return out

    def recv_frame(self, timeout: Optional[float] = None) -> Tuple[int, bytes]:
        if timeout is not None:
            self.sock.settimeout(timeout)
        taken: list[bytes] = []

        def read(n: int) -> bytes:
            taken.append(self._read(n))
            return taken[-1]

        try:
            b1, b2 = read(2)
            opcode, n = b1 & 0x0F, b2 & 0x7F
            if n == 126:
                n = struct.unpack(">H", read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", read(8))[0]
            payload = read(n)
        except (socket.timeout, BlockingIOError):
            # A timeout in the middle of a frame must not lose its header: put back what was read.
            self._buf = b"".join(taken) + self._buf
            raise
        if opcode == 8:
            raise WSClosed(f"close frame {payload[:2].hex()} {payload[2:].decode(errors='replace')}")
        if opcode == 9:  # ping -> pong
            self.send_frame(payload, 10)
            return self.recv_frame(timeout)
        return opcode, payload

    def recv(self, timeout: float = 5.0) -> Any:
        """Next message, decoded (text JSON or binary CBOR)."""
        opcode, payload = self.recv_frame(timeout)
        if opcode == 2:
            return cbor2.loads(payload)
        return json.loads(payload.decode("utf-8"))

    def recv_until(self, predicate: Any, timeout: float = 5.0) -> Any:
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no matching message")
            try:
                msg = self.recv(left)
            except socket.timeout:
                raise TimeoutError("no matching message")
            if predicate(msg):
                return msg

    def close(self) -> None:
        try:
            self.send_frame(b"\x03\xe8", 8)
        except OSError:
            pass
        self.sock.close()


def _mask_fast(payload: bytes, mask: bytes) -> bytes:
    n = len(payload)
    key = (mask * (n // 4 + 1))[:n]
    return (int.from_bytes(payload, "big") ^ int.from_bytes(key, "big")).to_bytes(n, "big")


Frame = Union[str, bytes]
