#!/usr/bin/env python3
"""ctest client.examples: builds examples/cpp/ the way an application is built, against hapticd
installed from the build directory into a temporary prefix and found through pkg-config, then
runs each example against a real daemon, the simulated delta of config/sim-delta-scene.yaml on
the realtime clock, and checks what each says it did (as tests/python/examples_test.py does for
the Python examples).

  examples_test.py --hapticd BIN --build-dir DIR --source-dir REPO --work-dir DIR
      (with /usr/bin/python3; the standard library only)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

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
    log_path = where / "hapticd.log"
    command = [str(hapticd), "run", "--config", config, "--socket", str(sock),
               "--duration", str(duration)]
    print("+", " ".join(command), flush=True)
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(command, cwd=root, stdout=log, stderr=subprocess.STDOUT)
        try:
            deadline = time.monotonic() + 20
            while not running(sock):
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"hapticd did not come up (exit {proc.poll()}):\n"
                                       + log_path.read_text(errors="replace"))
                time.sleep(0.1)
            yield sock
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            print(f"hapticd exited {proc.returncode}", flush=True)


class Examples:
    def __init__(self, bin_dir: Path, libdir: Path) -> None:
        self.bin_dir = bin_dir
        self.libdir = libdir
        self.failures: list[str] = []

    def run(self, name: str, sock: Path, *args: str) -> tuple[int, str]:
        command = [str(self.bin_dir / name), "--socket", str(sock), *args]
        print("+", " ".join(command), flush=True)
        done = subprocess.run(command, capture_output=True, text=True,
                              env=run_env(self.libdir), timeout=120)
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
    added = re.findall(r"^added wall (\d+)", out, re.M)
    removed = re.findall(r"^removed wall (\d+)", out, re.M)
    ex.expect("box_scene", rc == 0 and len(added) == 6 and sorted(removed) == sorted(added),
              f"adds six walls and removes each of them (added {added}, removed {removed})")

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
    latency = re.search(r"p50 [\d.]+ us, p99 [\d.]+ us", out)
    ex.expect("sine_wall", rc == 0 and counts is not None and int(counts[1]) > 0
              and counts[2] == "0" and latency is not None,
              "every move applied, the latency's p50 and p99 printed")


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
            ex = Examples(bin_dir, libdir)
            for name in EXAMPLES:
                problem = check_linked(bin_dir / name, libdir)
                ex.expect(name, problem is None, problem or "links the installed library")
            if ex.failures:
                raise RuntimeError("the examples do not link the installed library")
            with daemon(args.hapticd.resolve(), root, "config/sim-delta-scene.yaml", where,
                        args.duration) as sock:
                check_scene(ex, sock, where)
                check_moving_wall(ex, sock)
    except (RuntimeError, OSError, subprocess.SubprocessError) as e:
        print(f"examples_test: {e}", file=sys.stderr)
        return 1
    for failure in ex.failures:
        print(f"examples_test: FAILED {failure}", file=sys.stderr)
    return 1 if ex.failures else 0


if __name__ == "__main__":
    sys.exit(main())
