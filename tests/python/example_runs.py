"""What the examples' tests share (python.examples and client.examples): a daemon on the
simulated delta of config/sim-delta-scene.yaml, the examples run against it, and the checks of
what each says it did - the same for the Python examples and the C++ ones, which take the same
arguments and print the same summaries.
"""

from __future__ import annotations

import contextlib
import json
import re
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path


def running(sock: Path) -> bool:
    """Whether the daemon at ``sock`` answers status with its loop running."""
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(2)
            s.connect(str(sock))
            s.sendall(b'{"v":1,"cmd":"status"}\n')
            line = s.makefile("rb").readline()
        return json.loads(line).get("status", {}).get("state") == "running"
    except (OSError, ValueError):
        return False


@contextlib.contextmanager
def daemon(hapticd: Path, root: Path, where: Path, duration: float) -> Iterator[Path]:
    """``hapticd run`` of config/sim-delta-scene.yaml (realtime: moves and the state block go
    at the loop's real rate) serving a socket in ``where``; stopped (SIGTERM) on leaving."""
    sock = where / "s.sock"
    sock.unlink(missing_ok=True)
    log_path = where / "hapticd.log"
    command = [str(hapticd), "run", "--config", "config/sim-delta-scene.yaml", "--socket",
               str(sock), "--duration", str(duration)]
    print("+", " ".join(command), flush=True)
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(command, cwd=root, stdout=log, stderr=subprocess.STDOUT)
        try:
            deadline = time.monotonic() + 20
            while not running(sock):
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"hapticd did not come up (exit {proc.poll()}):\n"
                                       + log_path.read_text(errors="replace"))
                time.sleep(0.1)
            yield sock
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            print(f"hapticd exited {proc.returncode}", flush=True)


class Examples:
    """Runs example NAME as ``command(NAME) --socket SOCK ARGS`` with ``env``; keeps what
    failed."""

    def __init__(self, command: Callable[[str], list[str]], env: dict[str, str]) -> None:
        self.command = command
        self.env = env
        self.failures: list[str] = []

    def run(self, name: str, sock: Path, *args: str) -> tuple[int, str]:
        command = [*self.command(name), "--socket", str(sock), *args]
        print("+", " ".join(command), flush=True)
        done = subprocess.run(command, capture_output=True, text=True, env=self.env,
                              timeout=120)
        print(done.stdout + done.stderr, f"(exit {done.returncode})", flush=True)
        return done.returncode, done.stdout + done.stderr

    def expect(self, name: str, ok: bool, why: str) -> None:
        print(f"{'ok' if ok else 'FAIL'}: {name}: {why}", flush=True)
        if not ok:
            self.failures.append(f"{name}: {why}")


def check_scene(ex: Examples, sock: Path, where: Path, rate_hz: float = 1000.0,
                box_stiffness: float | None = None, axes: int = 3) -> None:
    """``rate_hz``: the daemon's loop rate; ``box_stiffness``: the box's K (None: the
    example's default); ``axes``: the device's task axes."""
    normal = [] if axes == 3 else ["--normal", ",".join(["1"] + ["0"] * (axes - 1))]
    rc, out = ex.run("too_stiff", sock, *normal)
    ex.expect("too_stiff", rc == 0 and "refused as expected (code 3)" in out,
              "exits 0 saying the gate refused the wall")

    stiffness = [] if box_stiffness is None else ["--stiffness", str(box_stiffness)]
    rc, out = ex.run("box_scene", sock, "--hold", "0.2", *stiffness)
    added = re.findall(r"^added wall (\d+)", out, re.M)
    removed = re.findall(r"^removed wall (\d+)", out, re.M)
    ex.expect("box_scene", rc == 0 and len(added) == 2 * axes and sorted(removed) == sorted(added),
              f"adds {2 * axes} walls and removes each of them (added {added}, removed {removed})")

    csv_path = where / "ticks.csv"
    rc, out = ex.run("logger", sock, "--duration", "2", "--output", str(csv_path))
    counts = re.search(r"read (\d+) samples, missed (\d+)", out)
    read, missed = (int(counts[1]), int(counts[2])) if counts else (0, -1)
    rows = len(csv_path.read_text().splitlines()) - 1 if csv_path.exists() else -1
    # 2 s of ticks (half of them at least); a reader descheduled longer than the ring holds may
    # miss a few.
    ex.expect("logger", rc == 0 and read > rate_hz and 0 <= missed <= max(5, read // 100)
              and rows == read, f"read {read} ticks in 2 s, missed {missed}, {rows} CSV rows")


def check_moving_wall(ex: Examples, sock: Path) -> None:
    rc, out = ex.run("sine_wall", sock, "--index", "0", "--amplitude", "0.004", "--duration", "2")
    counts = re.search(r"(\d+) applied, (\d+) not applied", out)
    latency = re.search(r"p50 [\d.]+ us, p99 [\d.]+ us", out)
    ex.expect("sine_wall", rc == 0 and counts is not None and int(counts[1]) > 0
              and counts[2] == "0" and latency is not None,
              "every move applied, the latency's p50 and p99 printed")


def run_all(ex: Examples, hapticd: Path, root: Path, where: Path, duration: float) -> int:
    """Every example against one daemon; the test's exit status."""
    try:
        with daemon(hapticd, root, where, duration) as sock:
            check_scene(ex, sock, where)
            check_moving_wall(ex, sock)
    except (RuntimeError, OSError, subprocess.SubprocessError) as e:
        print(f"examples_test: {e}", file=sys.stderr)
        return 1
    for failure in ex.failures:
        print(f"examples_test: FAILED {failure}", file=sys.stderr)
    return 1 if ex.failures else 0
