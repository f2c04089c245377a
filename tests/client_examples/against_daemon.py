#!/usr/bin/env python3
"""The Python and C++ examples against a daemon that is already running (the kernel test
machine's `hapticd run` on reference drives, tests/can/can_clients_kernel_test.cpp): each run
and checked as the simulated device's tests check them (tests/python/example_runs.py), the
Python ones from the repository's package (PYTHONPATH), the C++ ones built in the tree.

  against_daemon.py --socket SOCK --source-dir REPO --cpp-dir DIR --rate-hz HZ --axes M
                    [--box-stiffness K]
Exit 0 when every example did what it says.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from example_runs import Examples, check_moving_wall, check_scene  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", type=Path, required=True, help="the daemon's socket")
    parser.add_argument("--source-dir", type=Path, required=True, help="the repository")
    parser.add_argument("--cpp-dir", type=Path, required=True, help="the built C++ examples")
    parser.add_argument("--rate-hz", type=float, required=True, help="the daemon's loop rate")
    parser.add_argument("--axes", type=int, required=True, help="the device's task axes")
    parser.add_argument("--box-stiffness", type=float, help="the box's K (N/m)")
    args = parser.parse_args()
    root = args.source_dir.resolve()
    env = dict(os.environ)
    env["PYTHONPATH"] = str(root / "python")
    examples = root / "examples" / "python"
    failures = []
    for language, command in (
            ("python", lambda name: [sys.executable, str(examples / f"{name}.py")]),
            ("c++", lambda name: [str(args.cpp_dir / name)])):
        print(f"== the {language} examples", flush=True)
        ex = Examples(command, env)
        with tempfile.TemporaryDirectory(prefix="hapticd-examples-") as tmp:
            check_scene(ex, args.socket, Path(tmp), args.rate_hz, args.box_stiffness, args.axes)
            check_moving_wall(ex, args.socket)
        failures += [f"{language}: {f}" for f in ex.failures]
    for failure in failures:
        print(f"against_daemon: FAILED {failure}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
