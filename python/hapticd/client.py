"""Client of the daemon's control socket (protocol version 1, docs/operations.md).

One JSON object per line each way. ``request`` sends one and waits for its answer, so a
``Client`` is one conversation: use one per thread.
"""

from __future__ import annotations

import array
import collections
import itertools
import json
import math
import os
import socket
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

from .errors import ClientError, Refused
from .state import State

PROTOCOL_VERSION = 1
MAX_LINE_BYTES = 256 * 1024  # the daemon's limit on a request line
_MAX_ANSWER_BYTES = 4 * 1024 * 1024  # an answer line longer than this is no answer
_MAX_FDS = 4  # the daemon passes one; room to see (and close) a mistake


def _vector(field: str, value: Iterable[float]) -> list[float]:
    """1 to 3 finite numbers: the daemon refuses anything else, but here the message can
    name the argument before a round trip."""
    try:
        out = [float(x) for x in value]
    except (TypeError, ValueError) as e:
        raise ValueError(f"{field}: expected 1 to 3 numbers, got {value!r}") from e
    if not 1 <= len(out) <= 3:
        raise ValueError(f"{field}: expected 1 to 3 numbers, got {len(out)}")
    if not all(math.isfinite(x) for x in out):
        raise ValueError(f"{field}: {out} is not finite")
    return out


def _sample_of(raw: bytes) -> dict[str, Any] | None:
    """A stream line's sample ({"v": 1, "stream": {...}}: never an answer, which has "ok")."""
    if b'"stream"' not in raw:
        return None
    try:
        line = json.loads(raw)
    except ValueError:
        return None
    if not isinstance(line, dict) or "ok" in line or not isinstance(line.get("stream"), dict):
        return None
    return line["stream"]


def _wall(point: Iterable[float] | None = None, normal: Iterable[float] | None = None,
          **keys: Any) -> dict[str, Any]:
    wall: dict[str, Any] = {}
    if point is not None:
        wall["point"] = _vector("point", point)
    if normal is not None:
        wall["normal"] = _vector("normal", normal)
    wall.update({k: v for k, v in keys.items() if v is not None})
    return wall


class Client:
    """One connection to ``socket_path``. ``timeout`` (s) bounds each request; a scene
    request runs the passivity gate over the workspace (about 0.3 s on a delta), hence
    the generous default."""

    def __init__(self, socket_path: str | os.PathLike[str], timeout: float | None = 30.0) -> None:
        self.socket_path = os.fspath(socket_path)
        self.timeout = timeout
        self._ids = itertools.count(1)
        self._buffer = bytearray()
        self._fds: list[int] = []  # received with the answer being read
        self._broken = ""  # why the connection is unusable, once it is
        self._samples: collections.deque[dict[str, Any]] = collections.deque()  # stream lines
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._sock.settimeout(timeout)
        try:
            self._sock.connect(self.socket_path)
        except OSError as e:
            self._sock.close()
            why = "timed out" if isinstance(e, TimeoutError) else (e.strerror or str(e))
            raise ClientError(f"{self.socket_path}: cannot connect: {why}") from e

    def close(self) -> None:
        self._broken = self._broken or "closed"
        self._sock.close()
        self._close_fds()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _close_fds(self) -> None:
        for fd in self._fds:
            os.close(fd)
        self._fds.clear()

    def request(self, message: Mapping[str, Any]) -> dict[str, Any]:
        """Sends ``message`` (``v`` and ``id`` added) and returns the ``ok: true`` answer.
        Raises Refused on ``ok: false``, ClientError when no valid answer came."""
        answer, fds = self._exchange(message)
        for fd in fds:  # only ``state`` passes one
            os.close(fd)
        return answer

    def _exchange(self, message: Mapping[str, Any]) -> tuple[dict[str, Any], list[int]]:
        cmd = str(message.get("cmd", "?"))
        body = {"v": PROTOCOL_VERSION, "id": next(self._ids), **message}
        try:
            line = json.dumps(body, allow_nan=False, separators=(",", ":")).encode() + b"\n"
        except ValueError as e:
            raise ValueError(f"{cmd}: not valid JSON: {e}") from e
        if len(line) > MAX_LINE_BYTES:
            raise ValueError(f"{cmd}: the request is {len(line)} bytes, over the daemon's "
                             f"{MAX_LINE_BYTES}-byte limit")
        if self._broken:
            raise ClientError(f"{self.socket_path}: {cmd}: the connection failed earlier "
                              f"({self._broken}): open a new Client")
        self._close_fds()
        try:
            self._sock.sendall(line)
            raw = self._read_answer(cmd)
        except TimeoutError as e:
            raise self._fail(f"no answer to {cmd} within {self.timeout} s") from e
        except OSError as e:
            raise self._fail(f"{cmd}: {e.strerror or e}") from e
        except ClientError as e:
            raise self._fail(str(e).removeprefix(f"{self.socket_path}: ")) from None
        fds, self._fds = self._fds, []
        try:
            return self._parse(raw, body["id"], cmd), fds
        except BaseException as e:
            for fd in fds:
                os.close(fd)
            if isinstance(e, ClientError):  # out of step with the daemon from here on
                raise self._fail(str(e).removeprefix(f"{self.socket_path}: ")) from None
            raise

    def _fail(self, why: str) -> ClientError:
        """Closes the connection: a late answer would be taken for the next request's."""
        self._broken = why
        self.close()
        return ClientError(f"{self.socket_path}: {why}")

    def _read_line(self, cmd: str) -> bytes:
        while (end := self._buffer.find(b"\n")) < 0:
            if len(self._buffer) > _MAX_ANSWER_BYTES:
                raise ClientError(f"{self.socket_path}: {cmd}: an answer line over "
                                  f"{_MAX_ANSWER_BYTES} bytes")
            data, ancillary, flags, _ = self._sock.recvmsg(
                65536, socket.CMSG_SPACE(_MAX_FDS * array.array("i").itemsize))
            for level, kind, payload in ancillary:
                if level == socket.SOL_SOCKET and kind == socket.SCM_RIGHTS:
                    fds = array.array("i")
                    fds.frombytes(payload[:len(payload) - len(payload) % fds.itemsize])
                    self._fds.extend(fds)
            if flags & socket.MSG_CTRUNC:
                raise ClientError(f"{self.socket_path}: {cmd}: file descriptors truncated "
                                  f"(more than {_MAX_FDS} passed)")
            if not data:
                raise ClientError(f"{self.socket_path}: {cmd}: the daemon closed the "
                                  "connection" + (f" after {bytes(self._buffer)[:200]!r}"
                                                  if self._buffer else " without answering"))
            self._buffer += data
        raw = bytes(self._buffer[:end])
        del self._buffer[:end + 1]
        return raw

    def _read_answer(self, cmd: str) -> bytes:
        """The next line that is not a stream sample; those are kept for samples()."""
        while True:
            raw = self._read_line(cmd)
            sample = _sample_of(raw)
            if sample is None:
                return raw
            self._samples.append(sample)

    def stream(self, every: int) -> dict[str, Any]:
        """Starts the state stream: every ``every``-th tick's state as a line of its own on
        this connection (0 stops it); the answer's ``stream`` member (every, rate_hz,
        first_sample). Read the samples with samples()."""
        answer = self.request({"cmd": "stream", "every": int(every)})
        return self._member(answer, "stream", "stream")

    def samples(self, timeout: float | None = None) -> Iterator[dict[str, Any]]:
        """The stream's samples as they come (each line's ``stream`` member: tick, time_ns,
        measured_js, measured_cp, measured_cv, setpoint_cf, ..., missed), those that arrived
        during a request first; ends when none came within ``timeout`` s (None: the Client's
        timeout)."""
        wait = self.timeout if timeout is None else timeout
        while True:
            while self._samples:
                yield self._samples.popleft()
            if self._broken:
                raise ClientError(f"{self.socket_path}: stream: the connection failed earlier "
                                  f"({self._broken})")
            self._sock.settimeout(wait)
            try:
                raw = self._read_line("stream")
            except TimeoutError:
                return
            except OSError as e:
                raise self._fail(f"stream: {e.strerror or e}") from e
            except ClientError as e:
                raise self._fail(str(e).removeprefix(f"{self.socket_path}: ")) from None
            finally:
                if not self._broken:
                    self._sock.settimeout(self.timeout)
            sample = _sample_of(raw)
            if sample is None:
                raise self._fail(f"stream: a line that answers no request: {raw[:200]!r}")
            yield sample

    def _parse(self, raw: bytes, sent_id: int, cmd: str) -> dict[str, Any]:
        try:
            answer = json.loads(raw)
        except ValueError as e:
            raise ClientError(f"{self.socket_path}: {cmd}: the answer is not JSON ({e}): "
                              f"{raw[:200]!r}") from e
        if not isinstance(answer, dict):
            raise ClientError(f"{self.socket_path}: {cmd}: the answer is not an object: "
                              f"{raw[:200]!r}")
        if answer.get("v") != PROTOCOL_VERSION:
            raise ClientError(f"{self.socket_path}: {cmd}: answer's v is {answer.get('v')!r}, "
                              f"this client speaks {PROTOCOL_VERSION}")
        # An error about a request the daemon could not read may carry no id.
        unread = answer.get("ok") is False and answer.get("id") is None
        if answer.get("id") != sent_id and not unread:
            raise ClientError(f"{self.socket_path}: {cmd}: answer's id {answer.get('id')!r}, "
                              f"sent {sent_id}")
        if answer.get("ok") is True:
            return answer
        if answer.get("ok") is False:
            code = answer.get("code", 1)
            raise Refused(str(answer.get("error", "(no error given)")),
                          code if isinstance(code, int) else 1, cmd=cmd,
                          socket_path=self.socket_path)
        raise ClientError(f"{self.socket_path}: {cmd}: answer's ok is {answer.get('ok')!r}")

    def _member(self, answer: Mapping[str, Any], key: str, cmd: str) -> Any:
        if key not in answer:
            raise ClientError(f"{self.socket_path}: {cmd}: the answer has no {key!r}")
        return answer[key]

    def status(self) -> dict[str, Any]:
        return self._member(self.request({"cmd": "status"}), "status", "status")

    def stop(self) -> dict[str, Any]:
        return self.request({"cmd": "stop"})

    def clear_fault(self) -> dict[str, Any]:
        return self.request({"cmd": "clear-fault"})

    def reload(self, yaml_text: str, source: str = "python client") -> dict[str, Any]:
        """The ``reload`` member: accepted, applied_at_tick, gate."""
        answer = self.request({"cmd": "reload", "config": yaml_text, "source": source})
        return self._member(answer, "reload", "reload")

    def scene(self, op: str, **members: Any) -> dict[str, Any]:
        """Any scene request; returns the answer's ``scene`` member."""
        answer = self.request({"cmd": "scene", "op": op, **members})
        return self._member(answer, "scene", f"scene {op}")

    def _add(self, wall: dict[str, Any], keep: bool | None) -> int:
        members = {} if keep is None else {"keep": bool(keep)}
        index = self._member(self.scene("add", wall=wall, **members), "index", "scene add")
        if not isinstance(index, int):
            raise ClientError(f"{self.socket_path}: scene add: index {index!r} is no integer")
        return index

    def add_wall(self, point: Iterable[float], normal: Iterable[float], stiffness: float,
                 damping: float | None = None, keep: bool | None = None, **keys: Any) -> int:
        """Adds a wall (``keys``: more of a wall's keys, docs/kinematics.md); its index. It goes
        when this connection closes unless ``keep`` (None: as the daemon's
        safety.client_walls_on_leave says)."""
        wall = _wall(point, normal, stiffness=stiffness, damping=damping, **keys)
        return self._add(wall, keep)

    def add_attractor(self, point: Iterable[float], stiffness: float,
                      damping: float | None = None, max_force: float | None = None,
                      keep: bool | None = None, **keys: Any) -> int:
        """Adds an attractor: a spring-damper pulling the device to ``point`` along every task
        axis (bilateral, gated like a wall; docs/kinematics.md). ``max_force`` (N) bounds its
        force's norm (None: the joints' limits alone). Its index among the walls; it goes when
        this connection closes unless ``keep``, as a wall does."""
        wall = _wall(point, kind="attractor", stiffness=stiffness, damping=damping,
                     max_force=max_force, **keys)
        return self._add(wall, keep)

    def change_wall(self, index: int, **keys: Any) -> dict[str, Any]:
        """Changes only the keys given (point and normal as vectors)."""
        if not keys:
            raise ValueError("change_wall: no key to change")
        return self.scene("change", index=index, wall=_wall(**keys))

    def remove_wall(self, index: int) -> dict[str, Any]:
        """Removes wall ``index``; the later walls move down by one."""
        return self.scene("remove", index=index)

    def move_wall(self, index: int, point: Iterable[float]) -> dict[str, Any]:
        """Moves wall ``index``'s point. The answer carries applied_at_tick and
        applied_at_ns (CLOCK_MONOTONIC, as time.monotonic_ns()), null when no tick took it."""
        return self.scene("move", index=index, point=_vector("point", point))

    def servo_cf(self, force: Iterable[float]) -> dict[str, Any]:
        """Commands a force (N, one number per task axis; CRTK's servo_cf), added to the walls'.
        Send it again within the daemon's safety.client_force_hold_ms or it fades to zero; it
        goes at once when this connection closes. The answer says the force taken (saturated
        to safety.client_force_limit, and whether it was)."""
        return self._member(self.request({"cmd": "servo_cf", "force": _vector("force", force)}),
                            "servo_cf", "servo_cf")

    def state(self) -> State:
        """The state block, mapped; close it when done (a context manager)."""
        answer, fds = self._exchange({"cmd": "state"})
        if len(fds) != 1:
            for fd in fds:
                os.close(fd)
            raise ClientError(f"{self.socket_path}: state: the answer came with {len(fds)} "
                              "file descriptors, expected one (the state block)")
        description = answer.get("state")
        if not isinstance(description, dict):
            os.close(fds[0])
            raise ClientError(f"{self.socket_path}: state: the answer has no 'state' object")
        return State(fds[0], expect=description, name=f"{self.socket_path}: state block")
