#!/usr/bin/env python3
"""ctest python.examples: runs examples/python/ against a real daemon, the simulated delta of
config/sim-delta-scene.yaml (the configuration made for clients: a hand resting on a floor
whose walls may be moved) on the realtime clock, each with the installed package, and checks
what each says it did (example_runs.py, shared with the C++ examples' test).

  examples_test.py --hapticd BIN --source-dir REPO --work-dir DIR   (with /usr/bin/python3)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from example_runs import Examples, run_all
from run_package_tests import clean_env, make_venv


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hapticd", type=Path, required=True, help="the daemon's binary")
    parser.add_argument("--source-dir", type=Path, required=True, help="the repository")
    parser.add_argument("--work-dir", type=Path, required=True, help="where the venv goes")
    parser.add_argument("--duration", type=float, default=30, help="the daemon's --duration")
    args = parser.parse_args()
    root = args.source_dir.resolve()
    args.work_dir.mkdir(parents=True, exist_ok=True)
    python = make_venv(args.work_dir / "venv-examples", root / "python")
    examples = root / "examples" / "python"
    ex = Examples(lambda name: [str(python), str(examples / f"{name}.py")], clean_env())
    with tempfile.TemporaryDirectory(prefix="hapticd-examples-") as tmp:
        return run_all(ex, args.hapticd, root, Path(tmp), args.duration)


if __name__ == "__main__":
    sys.exit(main())
