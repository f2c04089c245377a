#!/usr/bin/env python3
"""What readers of the state block cost the servo loop (BENCHMARKS.md, the state at the
loop's rate): `hapticd run` on the simulated delta of config/sim-delta-scene.yaml, on the
realtime clock, first with no reader, then with N reader processes each following every tick
(the C++ example logger, examples/cpp/), alternating, R rounds each; the loop's wake latency
and compute time percentiles from each run's summary, and what the readers read and missed.

  tools/state_readers_bench.py --hapticd build/service/hapticd \\
      --logger LOGGER [--readers 32] [--seconds 20] [--rounds 3] [--pin]

LOGGER: examples/cpp/logger built against the installed library (examples/cpp/README.md).

Measured, never asserted: run it as root on a quiet machine (SCHED_FIFO for the loop).
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def running(sock: Path, hapticd: Path) -> bool:
    ctl = hapticd.with_name("hapticctl")
    done = subprocess.run([str(ctl), "--socket", str(sock), "--json", "status"],
                          capture_output=True, text=True, check=False)
    return done.returncode == 0 and json.loads(done.stdout)["status"]["state"] == "running"


def one_run(hapticd: Path, logger: Path, readers: int, seconds: float, where: Path,
            pin: bool) -> dict:
    sock, summary = where / "s.sock", where / "summary.json"
    sock.unlink(missing_ok=True)
    daemon = subprocess.Popen([str(hapticd), "run", "--config",
                               str(ROOT / "config/sim-delta-scene.yaml"), "--socket", str(sock),
                               "--duration", str(seconds + 4), "--summary-json", str(summary),
                               *(["--set", "loop.cpu=1"] if pin else [])],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not running(sock, hapticd):
        if daemon.poll() is not None:
            raise RuntimeError("hapticd did not start")
        time.sleep(0.1)
    taskset = ["taskset", "-c", "0"] if pin else []
    procs = [subprocess.Popen([*taskset, str(logger), "--socket", str(sock), "--duration", str(seconds),
                               "--output", "/dev/null"], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True) for _ in range(readers)]
    read = missed = 0
    for p in procs:
        out, _ = p.communicate()
        m = re.search(r"read (\d+) samples, missed (\d+)", out)
        if m is None:
            raise RuntimeError(f"a reader said: {out}")
        read, missed = read + int(m[1]), missed + int(m[2])
    daemon.wait()
    s = json.loads(summary.read_text())
    return {"wake": s["wake_latency_us"], "compute": s["compute_us"], "read": read,
            "missed": missed, "overruns": s["counters"]["loop"]["overruns"]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hapticd", type=Path, required=True)
    parser.add_argument("--logger", type=Path, required=True)
    parser.add_argument("--readers", type=int, default=32)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--pin", action="store_true",
                        help="the loop on CPU 1 (loop.cpu), the readers on CPU 0")
    args = parser.parse_args()
    runs: dict[int, list[dict]] = {0: [], args.readers: []}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.rounds):
            for n in runs:
                runs[n].append(one_run(args.hapticd, args.logger, n, args.seconds, Path(tmp),
                                       args.pin))
    print(f"{'readers':>7} {'wake p50':>9} {'wake p99':>9} {'wake p99.9':>10} {'compute p50':>11} "
          f"{'compute p99':>11} {'overruns':>8} {'read':>9} {'missed':>6}   (us; median of "
          f"{args.rounds} runs of {args.seconds:g} s)")
    for n, rs in runs.items():
        med = lambda f: statistics.median(f(r) for r in rs)  # noqa: E731
        print(f"{n:>7} {med(lambda r: r['wake']['p50']):>9.1f} {med(lambda r: r['wake']['p99']):>9.1f}"
              f" {med(lambda r: r['wake']['p999']):>10.1f} {med(lambda r: r['compute']['p50']):>11.1f}"
              f" {med(lambda r: r['compute']['p99']):>11.1f} {med(lambda r: r['overruns']):>8.0f}"
              f" {sum(r['read'] for r in rs):>9} {sum(r['missed'] for r in rs):>6}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
