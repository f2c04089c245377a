#!/usr/bin/env python3
"""Builds a box of walls around the device where it is now (six walls for three task axes,
four for two), holds it a moment, then removes the walls again, the last added first so each
index still names its wall.

  python3 examples/python/box_scene.py --socket /tmp/hapticd.sock --half 0.03

Exit 0 when every wall was added and removed; a refusal's code otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time

import hapticd


def box(centre: tuple[float, ...], half: float) -> list[tuple[list[float], list[float]]]:
    """(point, normal) of each face. Inside a wall is n . (x - point) > 0: the normals point
    out of the box, so the device inside it is outside every wall."""
    faces = []
    for axis in range(len(centre)):
        for sign in (1.0, -1.0):
            point = list(centre)
            point[axis] += sign * half
            normal = [0.0] * len(centre)
            normal[axis] = sign
            faces.append((point, normal))
    return faces


def fmt(v: list[float]) -> str:
    return "[" + ", ".join(f"{x:.4f}" for x in v) + "]"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", required=True, help="the daemon's control socket")
    parser.add_argument("--half", type=float, default=0.03, help="half the box's side (m)")
    parser.add_argument("--stiffness", type=float, default=500.0, help="N/m (default 500)")
    parser.add_argument("--damping", type=float, default=0.05, help="N s/m (default 0.05)")
    parser.add_argument("--hold", type=float, default=0.5, help="s the box stays (0.5)")
    args = parser.parse_args()
    added: list[int] = []
    try:
        with hapticd.Client(args.socket) as client:
            with client.state() as state:
                sample = state.latest()
            if sample is None:
                print("box_scene: the loop has written no sample yet", file=sys.stderr)
                return 1
            print(f"box_scene: the device is at {fmt(list(sample.measured_cp))}")
            try:
                for point, normal in box(sample.measured_cp, args.half):
                    index = client.add_wall(point, normal, args.stiffness, args.damping)
                    added.append(index)
                    print(f"added wall {index}: point {fmt(point)}, normal {fmt(normal)}")
                time.sleep(args.hold)
            finally:
                while added:
                    answer = client.remove_wall(added[-1])
                    print(f"removed wall {added.pop()} at tick {answer.get('applied_at_tick')}"
                          f" ({answer.get('walls')} walls left)")
    except hapticd.Refused as e:
        print(f"box_scene: refused (code {e.code}): {e.error}", file=sys.stderr)
        return e.code
    except hapticd.ClientError as e:
        print(f"box_scene: {e}", file=sys.stderr)
        return 1
    print("box_scene: box built and removed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
