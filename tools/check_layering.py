#!/usr/bin/env python3
"""The layering of docs/architecture.md, checked on every source file of the project.

Each module may include the headers of the modules listed for it and nothing else; the core
(analysis, config, control, gate) includes no OS header and does no I/O. The build already
refuses most violations (each module's include root reaches only what it links,
cmake/modules.cmake); this check states the rules in one place and catches what include roots
cannot: a module that links a library for one header may not use its others.

Usage: check_layering.py [ROOT] [--inject FILE=INCLUDE ...]
  --inject pretends FILE (relative to ROOT) also has `#include "INCLUDE"`, so a test can prove
  a forbidden include is caught. Exit 0 when every rule holds, 1 with one line per violation.
"""
import argparse
import pathlib
import re
import sys

# Module folder -> the modules (first path component of a quoted include) it may include.
ALLOWED = {
    # The floor (monotonic clock, counters): every module may stand on it, it on nothing.
    "src/base": {"base"},
    "src/analysis": {"analysis", "base"},
    "src/config": {"config", "base"},
    "src/control": {"control", "analysis", "config", "base"},
    "src/gate": {"gate", "analysis", "config", "control", "base"},
    "src/telemetry": {"telemetry", "base"},
    "src/loop": {"loop", "control", "analysis", "config", "telemetry", "drivers", "base"},
    "src/verify": {"verify", "loop", "control", "analysis", "config", "sim", "drivers",
                   "telemetry", "base"},
    "src/service": None,  # main() wires everything
    "drivers": {"drivers", "config", "sim", "base"},
    "sim": {"sim", "drivers", "config", "telemetry", "base"},
    # Reference devices are written from a firmware's published source or a specification,
    # never from our codecs: a device that shares the driver's reading of a spec cannot find
    # where that reading is wrong (tests/reference/README.md).
    "tests/reference": {"reference"},
}

# Headers of another module that are off limits even where the module is linked: only the
# Device seam of drivers/ may be seen by the loop, verify and the simulator.
SEAM_ONLY = {
    "src/loop": {"drivers": ("drivers/device.h",)},
    "src/verify": {"drivers": ("drivers/device.h",)},
    "sim": {"drivers": ("drivers/device.h", "drivers/io/", "drivers/hid/", "drivers/can/",
                        "drivers/gpio/")},  # peers speak a driver's pure codec
}
SEAM_EXCEPTIONS = {"drivers/registry.h"}

# Where a bare `#include "x.h"` of a module may come from (its target's include paths could
# reach further): reference devices use the kernel test rig's helpers, never a driver's file.
BARE_FROM = {"tests/reference": ("tests/reference", "tests/kernel/support", "tests/support")}
ROOT = pathlib.Path(__file__).resolve().parents[1]

# The core does no I/O: no OS, logging or stream headers.
NO_OS = {"src/analysis", "src/config", "src/control", "src/gate"}
OS_HEADER = re.compile(
    r"^(unistd|fcntl|signal|poll|sched|pthread|dlfcn|termios|time|malloc|errno)\.h$|"
    r"^(sys|linux|net|netinet|arpa|systemd|hidapi|libusb-1\.0)/|^(hidapi|gpiod|libusb)|"
    r"^spdlog/|^(fstream|iostream)$")  # snprintf (<cstdio>) formats, it does no I/O
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]')


def module_of(rel):
    for folder in sorted(ALLOWED, key=len, reverse=True):
        if rel == folder or rel.startswith(folder + "/"):
            return folder
    return None


def includes(text):
    for number, line in enumerate(text.splitlines(), 1):
        m = INCLUDE.match(line)
        if m:
            yield number, m.group(1), m.group(2)


def violations(rel, text):
    module = module_of(rel)
    if module is None:
        return
    allowed = ALLOWED[module]
    for number, kind, header in includes(text):
        where = f"{rel}:{number}: "
        if kind == "<":
            if module in NO_OS and OS_HEADER.search(header):
                yield where + f"<{header}>: {module} is OS- and I/O-free"
            continue
        first = header.split("/", 1)[0]
        if "/" not in header:
            if module in BARE_FROM and not any(
                    (ROOT / d / header).exists() for d in BARE_FROM[module] + (rel.rsplit("/", 1)[0],)):
                yield where + f'"{header}": {module} may include by bare name only its own ' \
                    f'headers and those of {", ".join(BARE_FROM[module])}'
            continue  # a header next to this file
        if allowed is not None and first not in allowed:
            yield where + f'"{header}": {module} may not include {first}/'
            continue
        seam = SEAM_ONLY.get(module, {}).get(first)
        if seam and (header in SEAM_EXCEPTIONS or not header.startswith(seam)):
            yield where + f'"{header}": {module} may use only {", ".join(seam)} of {first}/'


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("root", nargs="?", default=pathlib.Path(__file__).resolve().parents[1])
    parser.add_argument("--inject", action="append", default=[])
    args = parser.parse_args()
    global ROOT
    root = ROOT = pathlib.Path(args.root)
    injected = {}
    for item in args.inject:
        path, _, header = item.partition("=")
        injected.setdefault(path, []).append(f'#include "{header}"')
    found = []
    for path in sorted(root.glob("**/*")):
        rel = path.relative_to(root).as_posix()
        if path.suffix not in (".h", ".cpp") or rel.startswith(("build", "fuzz/")):
            continue
        if rel.startswith("tests/") and not rel.startswith("tests/reference/"):
            continue
        text = path.read_text(errors="replace") + "\n" + "\n".join(injected.get(rel, []))
        found.extend(violations(rel, text))
    for line in found:
        print(line)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
