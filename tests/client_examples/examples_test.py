#!/usr/bin/env python3
"""ctest client.examples: builds examples/cpp/ the way an application is built, against hapticd
installed from the build directory into a temporary prefix and found through pkg-config, then
runs each example against a real daemon, the simulated delta of config/sim-delta-scene.yaml on
the realtime clock, and checks what each says it did (tests/python/example_runs.py, shared with
the Python examples' test).

  examples_test.py --hapticd BIN --build-dir DIR --source-dir REPO --work-dir DIR
      (with /usr/bin/python3; the standard library only)
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from example_runs import Examples, run_all  # noqa: E402

EXAMPLES = ("sine_wall", "logger", "box_scene", "too_stiff")


def step(command: list[str], **kwargs: object) -> None:
    """Runs a build step, its output shown only when it fails (then the test fails)."""
    print("+", " ".join(command), flush=True)
    done = subprocess.run(command, capture_output=True, text=True, timeout=600,
                          **kwargs)  # type: ignore[call-overload]
    if done.returncode != 0:
        raise RuntimeError(f"{command[0]} exited {done.returncode}:\n{done.stdout}{done.stderr}")


def install(cmake: str, build_dir: Path, prefix: Path) -> Path:
    """Installs the project into ``prefix``; the directory of the installed library (where
    hapticd-client.pc says it is, lib/ or lib/<multiarch>/)."""
    step([cmake, "--install", str(build_dir), "--prefix", str(prefix)])
    found = sorted(prefix.glob("**/pkgconfig/hapticd-client.pc"))
    if not found:
        raise RuntimeError(f"no hapticd-client.pc installed under {prefix}")
    libdir = found[0].parent.parent
    if not (libdir / "libhapticd-client.so").exists():
        raise RuntimeError(f"{found[0]} installed, but no libhapticd-client.so beside it")
    return libdir


def build_examples(cmake: str, cxx: str | None, source: Path, build: Path,
                   libdir: Path) -> Path:
    """Configures and builds examples/cpp against the installed library alone, warnings as
    errors; the directory of the executables."""
    if build.exists():
        shutil.rmtree(build)
    env = {k: v for k, v in os.environ.items() if k not in ("PKG_CONFIG_LIBDIR", "CXXFLAGS",
                                                           "LDFLAGS", "LD_LIBRARY_PATH")}
    # Only the temporary prefix: a hapticd installed on the machine must not be the one found.
    env["PKG_CONFIG_PATH"] = str(libdir / "pkgconfig")
    configure = [cmake, "-S", str(source / "examples" / "cpp"), "-B", str(build),
                 "-DCMAKE_BUILD_TYPE=Release", "-DHAPTICD_EXAMPLES_WERROR=ON"]
    if cxx:
        configure.append(f"-DCMAKE_CXX_COMPILER={cxx}")
    step(configure, env=env)
    step([cmake, "--build", str(build), "--parallel", "2"], env=env)
    return build


def run_env(libdir: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["LD_LIBRARY_PATH"] = str(libdir)
    return env


def check_linked(exe: Path, libdir: Path) -> str | None:
    """None when ``exe`` loads libhapticd-client from ``libdir``; what it loads otherwise (the
    build tree's copy or one installed on the machine would hide a broken installation)."""
    done = subprocess.run(["ldd", str(exe)], capture_output=True, text=True, env=run_env(libdir),
                          timeout=60)
    loaded = re.search(r"libhapticd-client\.so\S* => (\S+)", done.stdout)
    if loaded is None:
        return f"ldd shows no libhapticd-client:\n{done.stdout}{done.stderr}"
    if Path(loaded[1]).resolve().parent != libdir.resolve():
        return f"loads {loaded[1]}, not the one installed in {libdir}"
    return None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hapticd", type=Path, required=True, help="the daemon's binary")
    parser.add_argument("--build-dir", type=Path, required=True,
                        help="the project's build directory, installed from")
    parser.add_argument("--source-dir", type=Path, required=True, help="the repository")
    parser.add_argument("--work-dir", type=Path, required=True,
                        help="where the examples are built")
    parser.add_argument("--duration", type=float, default=40, help="the daemon's --duration")
    parser.add_argument("--cmake", default=shutil.which("cmake") or "cmake",
                        help="cmake (default: the one on PATH)")
    parser.add_argument("--cxx", help="the C++ compiler (default: CMake's choice)")
    args = parser.parse_args()
    root = args.source_dir.resolve()
    args.work_dir.mkdir(parents=True, exist_ok=True)
    try:
        with tempfile.TemporaryDirectory(prefix="hapticd-cpp-examples-") as tmp:
            where = Path(tmp)
            libdir = install(args.cmake, args.build_dir.resolve(), where / "prefix")
            bin_dir = build_examples(args.cmake, args.cxx, root,
                                     args.work_dir.resolve() / "build-examples", libdir)
            for name in EXAMPLES:
                if problem := check_linked(bin_dir / name, libdir):
                    print(f"examples_test: {name}: {problem}", file=sys.stderr)
                    return 1
            ex = Examples(lambda name: [str(bin_dir / name)], run_env(libdir))
            return run_all(ex, args.hapticd.resolve(), root, where, args.duration)
    except (RuntimeError, OSError, subprocess.SubprocessError) as e:
        print(f"examples_test: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
