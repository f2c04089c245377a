#!/usr/bin/env python3
"""Reads every tick of the servo loop from the state block for a while and writes it as CSV
(tick, time, x, v, f, contact), then says how many it read and how many it missed.

  python3 examples/python/logger.py --socket /tmp/hapticd.sock --duration 2 --output ticks.csv
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import sys
import time

import hapticd


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", required=True, help="the daemon's control socket")
    parser.add_argument("--duration", type=float, default=2.0, help="s (default 2)")
    parser.add_argument("--output", default="-", help="CSV file (default: standard output)")
    args = parser.parse_args()
    # The count goes where the CSV does not, so standard output stays CSV alone.
    report = sys.stderr if args.output == "-" else sys.stdout
    try:
        with contextlib.ExitStack() as stack:
            client = stack.enter_context(hapticd.Client(args.socket))
            state = stack.enter_context(client.state())
            out = sys.stdout if args.output == "-" else stack.enter_context(
                open(args.output, "w", newline=""))
            writer = csv.writer(out)
            writer.writerow(["tick", "time_ns",
                             *(f"{q}{a}" for q in "xvf" for a in range(state.axes)), "contact"])
            follower = state.follow(until_ns=time.monotonic_ns() + int(args.duration * 1e9))
            for s in follower:
                writer.writerow([s.tick, s.time_ns, *s.x, *s.v, *s.f, s.wall_contact])
    except hapticd.HapticdError as e:
        print(f"logger: {e}", file=sys.stderr)
        return 1
    print(f"logger: read {follower.read} samples, missed {follower.missed} "
          f"({state.sample_period_ns / 1e6:g} ms period, {state.slots} slots)", file=report)
    return 0 if follower.read else 1


if __name__ == "__main__":
    sys.exit(main())
