#!/usr/bin/env python3
"""Asks for a wall far stiffer than the device can render passively and shows the passivity
gate refusing it, with the gate's numbers.

  python3 examples/python/too_stiff.py --socket /tmp/hapticd.sock --stiffness 1e7

Exit 0 when the gate refused it, 1 when it was accepted (then it is removed again) or
refused for another reason.
"""

from __future__ import annotations

import argparse
import math
import sys

import hapticd

GATE_REFUSED = 3  # the daemon's code for a refusal by the passivity gate


def numbers(text: str) -> list[float]:
    return [float(x) for x in text.split(",")]


def beyond_device(client: hapticd.Client, normal: list[float]) -> list[float]:
    """A point 1 cm from the device along ``normal``: the wall's face is within reach and
    the device is outside the wall (inside is n . (x - point) > 0)."""
    status = client.status()
    x, joints = status.get("task_position"), status.get("joints")
    if not x or not joints:
        raise hapticd.ClientError(f"{client.socket_path}: status has no task_position (a "
                                  "device of one joint?): give --point")
    # task_position has three numbers; the device's task axes are as many as its joints.
    if len(normal) != len(joints) or not any(normal):
        raise hapticd.ClientError(f"--normal: {len(joints)} numbers (the device's task axes), "
                                  "not zero")
    norm = math.hypot(*normal)
    return [p + 0.01 * n / norm for p, n in zip(x, normal)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", required=True, help="the daemon's control socket")
    parser.add_argument("--stiffness", type=float, default=1e7, help="N/m (default 1e7)")
    parser.add_argument("--damping", type=float, default=0.05, help="N s/m (default 0.05)")
    parser.add_argument("--point", type=numbers,
                        help="x,y,z (m), where the device can reach: a wall out of its reach "
                        "is passive at any stiffness (default: 1 cm beyond the device along "
                        "the normal)")
    parser.add_argument("--normal", type=numbers, default=[0.0, 0.0, 1.0], help="nx,ny,nz")
    args = parser.parse_args()
    try:
        with hapticd.Client(args.socket) as client:
            point = args.point or beyond_device(client, args.normal)
            try:
                index = client.add_wall(point, args.normal, args.stiffness, args.damping)
            except hapticd.Refused as e:
                if e.code != GATE_REFUSED:
                    print(f"too_stiff: refused, but not by the gate (code {e.code}): {e.error}")
                    return 1
                print(f"too_stiff: a {args.stiffness:g} N/m wall was refused as expected "
                      f"(code {e.code}): {e.error}")
                return 0
            print(f"too_stiff: a {args.stiffness:g} N/m wall was ACCEPTED as wall {index}: "
                  "removing it")
            client.remove_wall(index)
            return 1
    except hapticd.HapticdError as e:
        print(f"too_stiff: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
