"""An in-process stand-in for hapticd's control socket and state block, for the client's tests.

It speaks protocol version 1 as docs/operations.md states it (one JSON object per line each
way, the state block's memfd passed with SCM_RIGHTS on the answer's first bytes) and writes
the block as the daemon does, by the sequence lock, so the tests exercise the real reading.
"""

from __future__ import annotations

import fcntl
import json
import mmap
import os
import socket
import struct
import tempfile
import threading
from collections.abc import Callable
from typing import Any

HEADER = struct.Struct("<8sIIIIQIIQ")
SAMPLE = struct.Struct("<Qq18ddIIII")
F_SEAL_FUTURE_WRITE = getattr(fcntl, "F_SEAL_FUTURE_WRITE", 0x10)


class Block:
    """The state block, written by the test as the daemon's servo loop writes it."""

    def __init__(self, slots: int = 16, joints: int = 3, axes: int = 3,
                 period_ns: int = 1_000_000, magic: bytes = b"HAPTSTAT", layout: int = 1,
                 header_bytes: int = 128, slot_bytes: int = 192) -> None:
        self.slots, self.joints, self.axes = slots, joints, axes
        self.header_bytes, self.slot_bytes = header_bytes, slot_bytes
        self.size = header_bytes + slots * slot_bytes
        self.fd = os.memfd_create("hapticd-state-test", os.MFD_CLOEXEC | os.MFD_ALLOW_SEALING)
        os.ftruncate(self.fd, self.size)
        self.mm = mmap.mmap(self.fd, self.size)
        HEADER.pack_into(self.mm, 0, magic, layout, header_bytes, slot_bytes, slots, period_ns,
                         joints, axes, 0)
        # As the daemon's: no one may resize it, and no later mapping may write.
        fcntl.fcntl(self.fd, fcntl.F_ADD_SEALS, fcntl.F_SEAL_SHRINK | fcntl.F_SEAL_GROW
                    | F_SEAL_FUTURE_WRITE | fcntl.F_SEAL_SEAL)
        self.head = 0

    def description(self) -> dict[str, int]:
        """The ``state`` answer's member."""
        return {"layout": 1, "header_bytes": self.header_bytes, "slot_bytes": self.slot_bytes,
                "slots": self.slots, "sample_period_ns": 1_000_000, "joints": self.joints,
                "axes": self.axes}

    @staticmethod
    def values(n: int) -> tuple[Any, ...]:
        """Sample n's fields, each derived from n so a reader can check what it got."""
        vectors = (v for base in range(1, 7) for v in (base + n, base + n + 0.25, base + n + 0.5))
        return (1000 + n, 5_000_000 + n * 1_000_000, *vectors, n * 0.125, n & 0x7, n % 64, 0,
                0)

    def _slot(self, n: int) -> int:
        return self.header_bytes + (n % self.slots) * self.slot_bytes

    def begin(self, n: int) -> None:
        """Sample n half-written: its slot's seq odd, its first half new."""
        off = self._slot(n)
        struct.pack_into("<Q", self.mm, off, 2 * n + 1)
        self.mm[off + 8:off + 8 + 92] = SAMPLE.pack(*self.values(n))[:92]

    def write(self, n: int | None = None) -> int:
        """Writes sample n (default: the next) completely and publishes it in head."""
        n = self.head if n is None else n
        self.begin(n)
        off = self._slot(n)
        self.mm[off + 8:off + 8 + SAMPLE.size] = SAMPLE.pack(*self.values(n))
        struct.pack_into("<Q", self.mm, off, 2 * n + 2)
        self.set_head(max(self.head, n + 1))
        return n

    def set_head(self, head: int) -> None:
        self.head = head
        struct.pack_into("<Q", self.mm, 40, head)

    def set_seq(self, slot: int, seq: int) -> None:
        struct.pack_into("<Q", self.mm, self.header_bytes + slot * self.slot_bytes, seq)

    def close(self) -> None:
        self.mm.close()
        os.close(self.fd)


Handler = Callable[[dict[str, Any]], dict[str, Any] | None]


class FakeDaemon:
    """Serves a Unix socket in a thread; ``handler`` turns each request into the answer's
    members (``{"ok": False, ...}`` for a refusal; None: no answer at all; ``_lines_before``:
    lines sent before the answer, as a state stream's are). Every request read is kept in
    ``requests``."""

    def __init__(self, handler: Handler, block: Block | None = None) -> None:
        self.handler = handler
        self.block = block
        self.requests: list[dict[str, Any]] = []
        self._dir = tempfile.TemporaryDirectory(prefix="hapticd-fake-")
        self.path = os.path.join(self._dir.name, "control.sock")
        self._server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._server.bind(self.path)
        self._server.listen()
        self._conns: list[socket.socket] = []
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            self._conns.append(conn)
            threading.Thread(target=self._converse, args=(conn,), daemon=True).start()

    def _converse(self, conn: socket.socket) -> None:
        with conn, conn.makefile("rb") as lines:
            for line in lines:
                request = json.loads(line)
                self.requests.append(request)
                members = self.handler(request)
                if members is None:
                    continue
                # Lines the daemon sends unasked (a state stream's), here just before the answer.
                before = members.pop("_lines_before", [])
                answer = {"v": 1, "id": request.get("id"), "ok": True, **members}
                data = "".join(json.dumps(x) + "\n" for x in before).encode()
                data += (json.dumps(answer) + "\n").encode()
                try:
                    if request.get("cmd") == "state" and self.block is not None:
                        # The descriptor rides on the answer's first bytes, as the daemon's.
                        socket.send_fds(conn, [data[:5]], [self.block.fd])
                        conn.sendall(data[5:])
                    else:
                        conn.sendall(data)
                except OSError:
                    return

    def drop_connections(self, how: int = socket.SHUT_RDWR) -> None:
        for conn in self._conns:
            try:
                conn.shutdown(how)
            except OSError:  # that conversation is over already
                pass

    def close(self) -> None:
        self._server.shutdown(socket.SHUT_RDWR)  # wakes the accept (closing it would not)
        self._server.close()
        self.drop_connections()
        self._thread.join(timeout=5)
        self._dir.cleanup()

    def __enter__(self) -> FakeDaemon:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def refuse(error: str, code: int) -> dict[str, Any]:
    return {"ok": False, "error": error, "code": code}
