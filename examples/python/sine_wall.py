#!/usr/bin/env python3
"""Moves a wall along its normal by a sine, one move every 10 ms (100 Hz), and prints how long
a move takes from the send to the tick that applied it (p50/p99). The sine is centred where
the wall is when it starts (the status answer says each wall's point and normal):

  python3 examples/python/sine_wall.py --socket /tmp/hapticd.sock --index 0 \\
      --amplitude 0.005 --frequency 0.5 --duration 3

Exit 0 when every move was applied, 1 otherwise (a refusal's code when refused).
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import hapticd


def numbers(text: str) -> list[float]:
    return [float(x) for x in text.split(",")]


def percentile(ordered: list[int], q: float) -> int:
    """Nearest rank: a value that was measured, not an interpolation."""
    return ordered[min(len(ordered) - 1, max(0, math.ceil(q * len(ordered)) - 1))]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", required=True, help="the daemon's control socket")
    parser.add_argument("--index", type=int, default=0, help="the wall to move (default 0)")
    parser.add_argument("--point", type=numbers,
                        help="the sine's centre, x,y,z (m; default: where the wall is)")
    parser.add_argument("--normal", type=numbers,
                        help="the direction it moves along (default: the wall's normal)")
    parser.add_argument("--amplitude", type=float, default=0.005, help="m (default 0.005)")
    parser.add_argument("--frequency", type=float, default=0.5, help="Hz (default 0.5)")
    parser.add_argument("--duration", type=float, default=3.0, help="s (default 3)")
    parser.add_argument("--rate", type=float, default=100.0, help="moves a second (100)")
    args = parser.parse_args()
    if args.point is None or args.normal is None:
        try:
            with hapticd.Client(args.socket) as client:
                walls = client.status().get("walls") or []
        except hapticd.HapticdError as e:
            print(f"sine_wall: {e}", file=sys.stderr)
            return 1
        if args.index >= len(walls):
            print(f"sine_wall: the daemon has {len(walls)} walls, no wall {args.index}",
                  file=sys.stderr)
            return 2
        args.point = args.point or walls[args.index]["point"]
        args.normal = args.normal or walls[args.index]["normal"]
    norm = math.hypot(*args.normal)
    if len(args.point) != len(args.normal) or norm == 0:
        parser.error("--point and --normal: as many numbers each, the normal not zero")
    normal = [n / norm for n in args.normal]
    period_ns = round(1e9 / args.rate)
    moves = int(args.duration * args.rate)

    def place(t_ns: int) -> list[float]:
        s = args.amplitude * math.sin(2 * math.pi * args.frequency * t_ns / 1e9)
        return [p + s * n for p, n in zip(args.point, normal)]

    latencies: list[int] = []
    not_applied = late = 0
    try:
        with hapticd.Client(args.socket) as client:
            start = time.monotonic_ns()
            for k in range(moves + 1):  # the last one puts the wall back where it was
                due = start + k * period_ns
                now = time.monotonic_ns()
                if due > now:
                    time.sleep((due - now) / 1e9)
                elif now - due > period_ns:
                    late += 1
                point = place(k * period_ns) if k < moves else args.point
                sent = time.monotonic_ns()
                applied = client.move_wall(args.index, point).get("applied_at_ns")
                if applied is None:
                    not_applied += 1
                else:
                    latencies.append(applied - sent)
    except hapticd.Refused as e:
        print(f"sine_wall: move refused (code {e.code}): {e.error}", file=sys.stderr)
        return e.code
    except hapticd.ClientError as e:
        print(f"sine_wall: {e}", file=sys.stderr)
        return 1
    print(f"sine_wall: wall {args.index} moved {moves + 1} times along {normal} by "
          f"{args.amplitude * 1e3:g} mm at {args.frequency:g} Hz over {args.duration:g} s: "
          f"{len(latencies)} applied, {not_applied} not applied, {late} sent late")
    if latencies:
        ordered = sorted(latencies)
        print("send->applied latency: " + ", ".join(
            f"{name} {percentile(ordered, q) / 1e3:.1f} us"
            for name, q in (("p50", 0.5), ("p99", 0.99), ("max", 1.0))))
    return 0 if latencies and not not_applied else 1


if __name__ == "__main__":
    sys.exit(main())
