"""Reader of the daemon's state block: a shared ring of the servo loop's samples.

The daemon writes one sample a tick into a sealed memfd it passes over the control socket
(``Client.state()``). Reading is a sequence lock, so a reader never blocks or slows the
real-time thread: it copies a slot and keeps the copy only if the slot's sequence number was
the one sample n completes with, both before and after the copy.
"""

from __future__ import annotations

import enum
import mmap
import os
import struct
import sys
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from .errors import StateError

MAGIC = b"HAPTSTAT"
LAYOUT = 1
HEADER_BYTES = 128
SLOT_BYTES = 192

# magic, layout, header_bytes, slot_bytes, slots, sample_period_ns, joints, axes, head
_HEADER = struct.Struct("<8sIIIIQIIQ")
_HEAD_WORD = 40 // 8
# tick, time_ns, q[3], qd[3], effort[3], x[3], v[3], f[3], observer_energy_j,
# flags, wall_contact, fault_cause, reserved: the slot's bytes after its u64 seq.
_SAMPLE = struct.Struct("<Qq18ddIIII")
_SAMPLE_OFFSET = 8
_TOTAL_LIMIT = 2**62  # a sample number past this is no counter the daemon wrote


class TickFlag(enum.IntFlag):
    """The tick log's TickFlag bits (src/telemetry/tick_record.h), as ``Sample.flags``."""

    CONTACT = 1 << 0
    SATURATED = 1 << 1
    FAULT = 1 << 2
    OVERRUN = 1 << 3
    NO_PULL_CLAMPED = 1 << 4
    STALE = 1 << 5
    UNARMED = 1 << 6
    NON_FINITE = 1 << 7
    SEQUENCE_GAP = 1 << 8
    NO_POSITION = 1 << 9
    PASSIVITY_DAMPED = 1 << 10
    STEPPED = 1 << 11
    HELD = 1 << 12
    RUNAWAY = 1 << 13
    PROBE = 1 << 14


class JointState(NamedTuple):
    """CRTK's ``measured_js``: one entry per joint."""

    position: tuple[float, ...]
    velocity: tuple[float, ...]
    effort: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class Sample:
    """One tick of the servo loop. Vectors have as many entries as the device has
    joints (q, qd, effort) or task axes (x, v, f)."""

    index: int  # the sample's number in the block (sample n of ``State.head``)
    tick: int
    time_ns: int  # CLOCK_MONOTONIC of the tick's wake-up: compare with time.monotonic_ns()
    q: tuple[float, ...]
    qd: tuple[float, ...]
    effort: tuple[float, ...]
    x: tuple[float, ...]  # task position (m)
    v: tuple[float, ...]  # task velocity (m/s)
    f: tuple[float, ...]  # task force commanded (N)
    observer_energy_j: float
    flags: TickFlag
    wall_contact: int  # bit i: wall i in contact
    fault_cause: int  # 0: no fault

    @property
    def measured_js(self) -> JointState:
        return JointState(self.q, self.qd, self.effort)

    @property
    def measured_cp(self) -> tuple[float, ...]:
        return self.x

    @property
    def measured_cv(self) -> tuple[float, ...]:
        return self.v

    @property
    def setpoint_cf(self) -> tuple[float, ...]:
        return self.f

    def in_contact(self, wall: int) -> bool:
        return bool(self.wall_contact >> wall & 1)


class _Read(enum.Enum):
    OK = 0
    PENDING = 1  # not complete yet: being written, or head counted it before its slot
    LOST = 2  # overwritten by a later sample: the reader fell a whole ring behind


class State:
    """The state block, mapped read-only. Owns ``fd``: it is closed once mapped.

    ``expect`` is the ``state`` answer's description; a header that disagrees with it is
    refused, as is any header this package cannot read.
    """

    def __init__(self, fd: int, *, expect: Mapping[str, Any] | None = None,
                 name: str = "state block") -> None:
        self.name = name
        self._mm: mmap.mmap | None = None
        self._words: memoryview | None = None
        try:
            size = os.fstat(fd).st_size
            if size < HEADER_BYTES:
                raise StateError(f"{name}: {size} bytes, smaller than the {HEADER_BYTES}-byte "
                                 "header: not a hapticd state block")
            self._mm = mmap.mmap(fd, size, flags=mmap.MAP_SHARED, prot=mmap.PROT_READ)
        except OSError as e:
            raise StateError(f"{name}: cannot map it: {e}") from e
        finally:
            os.close(fd)
        try:
            self._check_header(size, expect or {})
        except StateError:
            self.close()
            raise

    @classmethod
    def open(cls, path: str | os.PathLike[str], *,
             expect: Mapping[str, Any] | None = None) -> State:
        """A block in a file (a copy of one, or a test's)."""
        try:
            fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
        except OSError as e:
            raise StateError(f"{os.fspath(path)}: cannot open it: {e.strerror}") from e
        return cls(fd, expect=expect, name=os.fspath(path))

    def _check_header(self, size: int, expect: Mapping[str, Any]) -> None:
        assert self._mm is not None
        (magic, layout, self.header_bytes, self.slot_bytes, self.slots, self.sample_period_ns,
         self.joints, self.axes, _) = _HEADER.unpack_from(self._mm, 0)
        name = self.name
        if magic != MAGIC:
            raise StateError(f"{name}: magic {magic!r}, expected {MAGIC!r}: "
                             "not a hapticd state block")
        if layout != LAYOUT:
            raise StateError(f"{name}: layout {layout}, this package reads layout {LAYOUT}: "
                             "a hapticd package of the daemon's version reads it")
        if self.header_bytes < HEADER_BYTES or self.header_bytes % 8:
            raise StateError(f"{name}: header_bytes {self.header_bytes}, expected "
                             f"{HEADER_BYTES} (or more, a multiple of 8)")
        if self.slot_bytes < SLOT_BYTES or self.slot_bytes % 8:
            raise StateError(f"{name}: slot_bytes {self.slot_bytes}, expected {SLOT_BYTES} "
                             "(or more, a multiple of 8)")
        if self.slots == 0 or self.slots & (self.slots - 1):
            raise StateError(f"{name}: slots {self.slots} is not a power of two")
        for field, n in (("joints", self.joints), ("axes", self.axes)):
            if not 1 <= n <= 3:
                raise StateError(f"{name}: {field} {n}, expected 1 to 3")
        total = self.header_bytes + self.slots * self.slot_bytes
        if size < total:
            raise StateError(f"{name}: {size} bytes, its header describes {total}")
        for field in ("layout", "header_bytes", "slot_bytes", "slots", "sample_period_ns",
                      "joints", "axes"):
            said = expect.get(field)
            found = layout if field == "layout" else getattr(self, field)
            if said is not None and said != found:
                raise StateError(f"{name}: header's {field} {found} differs from the "
                                 f"daemon's answer's {said}")
        if sys.byteorder != "little":  # the words are read natively: atomic 8-byte loads
            raise StateError(f"{name}: a little-endian layout on a {sys.byteorder}-endian host")
        self._words = memoryview(self._mm)[:total].cast("Q")

    @property
    def head(self) -> int:
        """How many samples the daemon has written; sample n is in slot n % slots."""
        return self._live_words()[_HEAD_WORD]

    def _live_words(self) -> memoryview:
        if self._words is None:
            raise StateError(f"{self.name}: closed")
        return self._words

    def _read(self, n: int) -> tuple[_Read, Sample | None]:
        words = self._live_words()
        assert self._mm is not None
        offset = self.header_bytes + (n % self.slots) * self.slot_bytes
        word = offset // 8
        done = 2 * n + 2
        seq = words[word]
        if seq == done:
            raw = self._mm[offset + _SAMPLE_OFFSET:offset + _SAMPLE_OFFSET + _SAMPLE.size]
            seq = words[word]
            if seq == done:
                return _Read.OK, self._sample(n, raw)
        return (_Read.LOST if seq > done else _Read.PENDING), None

    def _sample(self, n: int, raw: bytes) -> Sample:
        t = _SAMPLE.unpack(raw)
        j, m = self.joints, self.axes
        return Sample(index=n, tick=t[0], time_ns=t[1], q=t[2:2 + j], qd=t[5:5 + j],
                      effort=t[8:8 + j], x=t[11:11 + m], v=t[14:14 + m], f=t[17:17 + m],
                      observer_energy_j=t[20], flags=TickFlag(t[21]), wall_contact=t[22],
                      fault_cause=t[23])

    def read(self, n: int) -> Sample | None:
        """Sample n, or None when it is not complete or was already overwritten."""
        status, sample = self._read(n)
        return sample if status is _Read.OK else None

    def latest(self, attempts: int = 100) -> Sample | None:
        """The newest complete sample; None before the first. A slot being written is
        skipped for the one before it rather than waited for."""
        for _ in range(attempts):
            head = self.head
            if head == 0:
                return None
            if head > _TOTAL_LIMIT:
                raise StateError(f"{self.name}: head {head} is no sample count")
            for n in range(head - 1, max(head - 3, -1), -1):
                status, sample = self._read(n)
                if status is _Read.OK:
                    return sample
                if status is _Read.LOST:
                    break  # the writer lapped this reader: start again from the new head
        raise StateError(f"{self.name}: no complete sample in {attempts} attempts "
                         f"(head {self.head}): is the writer stuck mid-sample?")

    def follow(self, *, start: int | None = None, until_ns: int | None = None,
               poll_s: float = 0.01) -> Follower:
        """Every sample from ``start`` (default: the next one written) on, in order."""
        return Follower(self, self.head if start is None else start, until_ns, poll_s)

    def close(self) -> None:
        if self._words is not None:
            self._words.release()
            self._words = None
        if self._mm is not None:
            self._mm.close()
            self._mm = None

    def __enter__(self) -> State:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"State({self.name!r}, slots={self.slots}, joints={self.joints}, "
                f"axes={self.axes}, period={self.sample_period_ns} ns)")


class Follower(Iterator[Sample]):
    """Yields each sample once, in order; those overwritten before it could read them are
    counted in ``missed``. Sleeps ``poll_s`` only when it has caught up with the writer, so
    reading samples already there makes no system call. Ends at ``until_ns``
    (CLOCK_MONOTONIC): at the first sample that late, or when caught up past it."""

    def __init__(self, state: State, start: int, until_ns: int | None, poll_s: float) -> None:
        self.state = state
        self.next_index = start
        self.until_ns = until_ns
        self.poll_s = poll_s
        self.read = 0
        self.missed = 0
        self._ended = False

    def __next__(self) -> Sample:
        state = self.state
        while not self._ended:
            head = state.head
            if self.next_index < head:
                oldest = head - state.slots
                if self.next_index < oldest:
                    self.missed += oldest - self.next_index
                    self.next_index = oldest
                status, sample = state._read(self.next_index)
                if status is _Read.OK:
                    assert sample is not None
                    if self.until_ns is not None and sample.time_ns >= self.until_ns:
                        break
                    self.next_index += 1
                    self.read += 1
                    return sample
                if status is _Read.LOST:
                    self.missed += 1
                    self.next_index += 1
                    continue
            if self.until_ns is not None and time.monotonic_ns() >= self.until_ns:
                break
            time.sleep(self.poll_s)
        self._ended = True
        raise StopIteration
