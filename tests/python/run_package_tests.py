#!/usr/bin/env python3
"""ctest python.package: installs the package as a user would on Debian, offline (a venv
over the system's site-packages, pip with no index and no build isolation), then runs the
unittest suite with that venv's interpreter, so the tests import the installed package.

  run_package_tests.py --source-dir REPO --work-dir DIR    (run it with /usr/bin/python3)
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path


def clean_env() -> dict[str, str]:
    """The venv's interpreter alone decides what is imported; no bytecode in the checkout."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def run(command: list[str | Path], **kwargs: object) -> None:
    print("+", " ".join(map(str, command)), flush=True)
    subprocess.run(command, check=True, env=clean_env(), **kwargs)  # type: ignore[call-overload]


def make_venv(venv: Path, source: Path) -> Path:
    """A fresh venv at ``venv`` with the package at ``source`` installed; its python.
    pip builds in the tree it is given, so it gets a copy: the checkout stays clean and two
    tests may install at once."""
    copy = venv.with_name(venv.name + "-src")
    for old in (venv, copy):
        shutil.rmtree(old, ignore_errors=True)
    shutil.copytree(source, copy,
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    run([sys.executable, "-m", "venv", "--system-site-packages", venv])
    python = venv / "bin" / "python"
    run([python, "-m", "pip", "install", "--no-index", "--no-build-isolation", "--no-deps",
         "--disable-pip-version-check", copy])
    return python


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--source-dir", type=Path, required=True, help="the repository")
    parser.add_argument("--work-dir", type=Path, required=True, help="where the venv goes")
    args = parser.parse_args()
    args.work_dir.mkdir(parents=True, exist_ok=True)
    try:
        python = make_venv(args.work_dir / "venv-package", args.source_dir / "python")
        # From the work directory: the checkout's python/ is not on the path there.
        run([python, "-c", "import hapticd, sys; print('testing', hapticd.__file__); "
             "sys.exit(0 if sys.prefix in hapticd.__file__ else 'not the installed package')"],
            cwd=args.work_dir)
        run([python, "-m", "unittest", "discover", "-s", args.source_dir / "tests" / "python",
             "-v"], cwd=args.work_dir)
    except subprocess.CalledProcessError as e:
        print(f"run_package_tests: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
