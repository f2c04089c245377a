#!/usr/bin/env python3
"""ctest python.examples: runs examples/python/ against a real daemon, the simulated delta of
config/sim-delta-scene.yaml (the configuration made for clients: a hand resting on a floor
whose walls may be moved) on the realtime clock, so moves and the state block go at the loop's
real rate, each with the installed package, and checks what each says it did.

  examples_test.py --hapticd BIN --source-dir REPO --work-dir DIR   (with /usr/bin/python3)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from run_package_tests import clean_env, make_venv

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
def daemon(hapticd: Path, root: Path, config: str, where: Path,
           duration: float) -> Iterator[Path]:
    """``hapticd run`` serving a socket in ``where``; stopped (SIGTERM) on leaving."""
    sock = where / "s.sock"
    sock.unlink(missing_ok=True)
    log = open(where / "hapticd.log", "wb")
    command = [str(hapticd), "run", "--config", config, "--set", "loop.clock=realtime",
               "--socket", str(sock), "--duration", str(duration)]
    print("+", " ".join(command), flush=True)
    proc = subprocess.Popen(command, cwd=root, stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 20
        while not running(sock):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"hapticd did not come up (exit {proc.poll()}):\n"
                                   + (where / "hapticd.log").read_text(errors="replace"))
            time.sleep(0.1)
        yield sock
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()
        print(f"hapticd exited {proc.returncode}", flush=True)


class Examples:
    def __init__(self, python: Path, root: Path) -> None:
        self.python = python
        self.dir = root / "examples" / "python"
        self.failures: list[str] = []

    def run(self, name: str, sock: Path, *args: str) -> tuple[int, str]:
        command = [str(self.python), str(self.dir / f"{name}.py"), "--socket", str(sock), *args]
        print("+", " ".join(command), flush=True)
        done = subprocess.run(command, capture_output=True, text=True, env=clean_env(),
                              timeout=120)
        print(done.stdout + done.stderr, f"(exit {done.returncode})", flush=True)
        return done.returncode, done.stdout + done.stderr

    def expect(self, name: str, ok: bool, why: str) -> None:
        print(f"{'ok' if ok else 'FAIL'}: {name}: {why}", flush=True)
        if not ok:
            self.failures.append(f"{name}: {why}")


def check_scene(ex: Examples, sock: Path, where: Path) -> None:
    rc, out = ex.run("too_stiff", sock)
    ex.expect("too_stiff", rc == 0 and "refused as expected (code 3)" in out,
              "exits 0 saying the gate refused the wall")

    rc, out = ex.run("box_scene", sock, "--hold", "0.2")
    added, removed = out.count("added wall"), out.count("removed wall")
    ex.expect("box_scene", rc == 0 and added == 6 and removed == 6,
              f"adds six walls and removes them (added {added}, removed {removed})")

    csv_path = where / "ticks.csv"
    rc, out = ex.run("logger", sock, "--duration", "2", "--output", str(csv_path))
    counts = re.search(r"read (\d+) samples, missed (\d+)", out)
    read, missed = (int(counts[1]), int(counts[2])) if counts else (0, -1)
    rows = len(csv_path.read_text().splitlines()) - 1 if csv_path.exists() else -1
    # 2 s at 1 kHz; a reader descheduled longer than the ring holds may miss a few.
    ex.expect("logger", rc == 0 and read > 1000 and 0 <= missed <= max(5, read // 100)
              and rows == read, f"read {read} ticks in 2 s, missed {missed}, {rows} CSV rows")


def check_moving_wall(ex: Examples, sock: Path) -> None:
    rc, out = ex.run("sine_wall", sock, "--index", "0", "--amplitude", "0.004", "--duration", "2")
    counts = re.search(r"(\d+) applied, (\d+) not applied", out)
    ex.expect("sine_wall", rc == 0 and counts is not None and int(counts[1]) > 0
              and counts[2] == "0" and "p50" in out and "p99" in out,
              "every move applied, the latency's p50 and p99 printed")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hapticd", type=Path, required=True, help="the daemon's binary")
    parser.add_argument("--source-dir", type=Path, required=True, help="the repository")
    parser.add_argument("--work-dir", type=Path, required=True, help="where the venv goes")
    parser.add_argument("--duration", type=float, default=30, help="each daemon's --duration")
    args = parser.parse_args()
    root = args.source_dir.resolve()
    args.work_dir.mkdir(parents=True, exist_ok=True)
    try:
        ex = Examples(make_venv(args.work_dir / "venv-examples", root / "python"), root)
        with tempfile.TemporaryDirectory(prefix="hapticd-examples-") as tmp:
            where = Path(tmp)
            with daemon(args.hapticd, root, "config/sim-delta-scene.yaml", where,
                        args.duration) as sock:
                check_scene(ex, sock, where)
                check_moving_wall(ex, sock)
    except (RuntimeError, subprocess.SubprocessError) as e:
        print(f"examples_test: {e}", file=sys.stderr)
        return 1
    for failure in ex.failures:
        print(f"examples_test: FAILED {failure}", file=sys.stderr)
    return 1 if ex.failures else 0


if __name__ == "__main__":
    sys.exit(main())
