#!/usr/bin/env python3
"""The layering of docs/architecture.md, checked on every source file of the project.

Each module may include the headers of the modules listed for it and nothing else; the core
(analysis, kinematics, config, control, gate) includes no OS header and does no I/O; of drivers/, the loop
and verify see the Device seam alone and the simulator the seam, the fd helpers and each
driver's pure codecs. The build already refuses what include roots can refuse
(cmake/modules.cmake; tests/layering/ probes every edge of the picture, with the table this
file prints); this check states the rules in one place, catches what include roots cannot (a
module that links a library for one header may not use its others), and keeps the picture in
docs/architecture.md equal to the rules.

Usage: check_layering.py [ROOT] [--inject FILE=INCLUDE ...] [--picture]
  --inject pretends FILE (relative to ROOT) also has `#include "INCLUDE"`, so a test can prove
  a forbidden include is caught. Exit 0 when every rule holds, 1 with one line per violation.
  --picture prints the modules and what each may use, one per line, for the build's probes:
  "module NAME: MODULE..." ("*" for everything), "only NAME drivers: HEADER...".
"""
import argparse
import pathlib
import re
import sys

# Module folder -> the modules (first path component of a quoted include) it may include.
ALLOWED = {
    # The floor (monotonic clock, counters, errno text, hex): every module may stand on it, it
    # on nothing.
    "src/base": {"base"},
    "src/analysis": {"analysis", "base"},
    # Multi-axis kinematics: free functions over fixed-size value types. The configuration
    # holds its parameters (device.kinematics), so whatever sees the configuration sees them.
    "src/kinematics": {"kinematics", "base"},
    "src/config": {"config", "kinematics", "base"},
    "src/control": {"control", "analysis", "config", "kinematics", "base"},
    "src/gate": {"gate", "analysis", "config", "kinematics", "control", "base"},
    # The state block's writer includes its layout from the client library.
    "src/telemetry": {"telemetry", "base", "client"},
    # What may use telemetry may use the state block's layout its writer takes (client).
    "src/loop": {"loop", "control", "analysis", "config", "kinematics", "telemetry", "drivers",
                 "base", "client"},
    "src/verify": {"verify", "loop", "control", "analysis", "config", "kinematics", "sim",
                   "drivers", "telemetry", "base", "client"},
    "drivers": {"drivers", "config", "kinematics", "base"},
    "sim": {"sim", "drivers", "config", "kinematics", "telemetry", "base", "client"},
    # The composition root: each driver's device joined with its simulated device.
    "wiring": {"wiring", "drivers", "sim", "config", "kinematics", "base"},
    "service": None,  # main() and the commands use everything
    # The client library applications link (installed on its own): nothing of the daemon, not
    # even the floor; its headers include each other by bare name.
    "client": set(),
    # Reference devices are written from a firmware's published source or a specification,
    # never from our codecs: a device that shares the driver's reading of a spec cannot find
    # where that reading is wrong (tests/reference/README.md).
    "tests/reference": {"reference"},
}
# The modules of the picture, in its order (tests/reference is no module of the daemon).
MODULES = ("base", "client", "analysis", "kinematics", "config", "control", "gate", "telemetry", "loop",
           "verify", "drivers", "sim", "wiring", "service")

# A driver's pure codecs: no OS header, no Device (checked below). A driver's simulated
# device speaks the driver's bytes through them, so both read the protocol the same way.
PURE_CODECS = (
    "drivers/can/can_frame.h", "drivers/can/canopen.h", "drivers/can/cia402.h",
    "drivers/can/odrive_protocol.h", "drivers/can/can_bus_load.h", "drivers/can/can_settings.h",
    "drivers/field/field.h", "drivers/field/field_schema.h", "drivers/hid/report_layout.h",
    "drivers/hid/report_descriptor.h", "drivers/hid/pid_protocol.h",
    "drivers/hid/descriptor_builder.h", "drivers/hid/hid_framing.h", "drivers/hid/hid_settings.h",
    "drivers/hid/hid_section_reading.h",
    "drivers/gpio/quadrature_decoder.h", "drivers/gpio/gpio_wire.h", "drivers/gpio/gpio_settings.h",
    "drivers/evdev/evdev_settings.h", "drivers/evdev/evdev_wire.h",
    "drivers/serial/checksum.h", "drivers/serial/serial_frame.h", "drivers/serial/serial_settings.h",
    "drivers/falcon/falcon_protocol.h",
)
# What a driver is given to build its device: a value type of the configuration, which a
# driver's settings (a pure codec) are read from.
DRIVER_CONTEXT = "drivers/driver_context.h"
SEAM = ("drivers/device.h", DRIVER_CONTEXT)
# The transports a driver and its simulated device both speak on: the fd helpers (an owning
# descriptor, the eventfd that stops a polling thread), and the SocketCAN socket the simulated
# drives send their frames through.
SHARED_TRANSPORTS = ("drivers/io/unique_fd.h", "drivers/io/stop_event.h", "drivers/can/can_socket.h")

# The only headers of drivers/ a module that may use drivers/ sees, where it may not see all.
ONLY_OF_DRIVERS = {
    "src/loop": SEAM,
    "src/verify": SEAM,
    "sim": SEAM + SHARED_TRANSPORTS + PURE_CODECS,
}

# Modules that name no driver (docs/devices.md, the driver registry): they reach a driver only
# through its registry entry, never a header of drivers/<name>/ or sim/peers/<name>/, and never
# compare device.driver with a driver's name.
NAMES_NO_DRIVER = {"service"}
DRIVER_HEADER = re.compile(r"^(drivers|sim/peers)/(?!io/)[^/]+/")
NAME_COMPARED = re.compile(r'[!=]=\s*"(\w+)"|"(\w+)"\s*[!=]=')


def driver_names(root):
    """sim and each folder of drivers/ with a CMakeLists.txt."""
    return {"sim"} | {p.parent.name for p in (root / "drivers").glob("*/CMakeLists.txt")}


# Where a bare `#include "x.h"` of a module may come from (its target's include paths could
# reach further): reference devices use the kernel test rig's helpers, never a driver's file.
BARE_FROM = {"tests/reference": ("tests/reference", "tests/kernel/support", "tests/support")}
ROOT = pathlib.Path(__file__).resolve().parents[1]

# The core does no I/O: no OS, logging or stream headers.
NO_OS = {"src/analysis", "src/kinematics", "src/config", "src/control", "src/gate"}
OS_HEADER = re.compile(
    r"^(unistd|fcntl|signal|poll|sched|pthread|dlfcn|termios|time|malloc|errno)\.h$|"
    r"^(sys|linux|net|netinet|arpa|systemd|hidapi|libusb-1\.0|libevdev)/|^(hidapi|gpiod|libusb)|"
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
            if (module in NO_OS or rel in PURE_CODECS) and OS_HEADER.search(header):
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
        only = ONLY_OF_DRIVERS.get(module)
        if first == "drivers" and only is not None and header not in only:
            yield where + f'"{header}": {module} may use of drivers/ only {", ".join(only)}'
        if module in NAMES_NO_DRIVER and DRIVER_HEADER.match(header):
            yield where + f'"{header}": {module} names no driver (ask its registry entry)'
        if rel in PURE_CODECS and first not in ("config", "base") and \
                header not in PURE_CODECS + (DRIVER_CONTEXT,):
            yield where + f'"{header}": a pure codec includes only config/, base/, the driver ' \
                'context and other ' \
                'pure codecs (no Device, no transport)'


def driver_name_comparisons(rel, text, names):
    for number, line in enumerate(text.splitlines(), 1):
        for m in NAME_COMPARED.finditer(line):
            name = m.group(1) or m.group(2)
            if name in names:
                yield f'{rel}:{number}: "{name}": {module_of(rel)} names no driver (ask its ' \
                    'registry entry)'


def name_of(folder):
    return folder.rsplit("/", 1)[-1]


def picture():
    """The modules and what each may use, for the build's probes (tests/layering/)."""
    lines = []
    for folder, allowed in ALLOWED.items():
        module = name_of(folder)
        if module not in MODULES:
            continue
        uses = "*" if allowed is None else " ".join(m for m in MODULES if m in allowed - {module})
        lines.append(f"module {module}: {uses}")
    for folder, only in ONLY_OF_DRIVERS.items():
        lines.append(f"only {name_of(folder)} drivers: {' '.join(only)}")
    return lines


# The table of docs/architecture.md: "| module | may use | ... |", one row per module.
DOC_ROW = re.compile(r"^\|\s*(\w+)\s*\|\s*([^|]*)\|")


def picture_differences(root):
    """Where docs/architecture.md's table of modules says other than ALLOWED."""
    doc = root / "docs" / "architecture.md"
    stated = {}
    for line in doc.read_text().splitlines():
        m = DOC_ROW.match(line)
        if m and m.group(1) in MODULES:
            cell = m.group(2).strip()
            uses = set(re.findall(r"\w+", cell)) & set(MODULES)
            stated[m.group(1)] = None if cell == "everything" else uses
    for folder, allowed in ALLOWED.items():
        module = name_of(folder)
        if module not in MODULES:
            continue
        want = None if allowed is None else allowed - {module}
        if module not in stated:
            yield f"docs/architecture.md: the table of modules has no row for {module}"
        elif stated[module] != want:
            said = "everything" if stated[module] is None else ", ".join(sorted(stated[module]))
            rule = "everything" if want is None else ", ".join(sorted(want))
            yield f"docs/architecture.md: {module} may use {rule}, the table says {said}"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("root", nargs="?", default=pathlib.Path(__file__).resolve().parents[1])
    parser.add_argument("--inject", action="append", default=[])
    parser.add_argument("--picture", action="store_true")
    args = parser.parse_args()
    if args.picture:
        print("\n".join(picture()))
        return 0
    global ROOT
    root = ROOT = pathlib.Path(args.root)
    injected = {}
    for item in args.inject:
        path, _, header = item.partition("=")
        injected.setdefault(path, []).append(f'#include "{header}"')
    found = list(picture_differences(root))
    for path in sorted(root.glob("**/*")):
        rel = path.relative_to(root).as_posix()
        if path.suffix not in (".h", ".cpp") or rel.startswith(("build", "fuzz/")):
            continue
        if rel.startswith("tests/") and not rel.startswith("tests/reference/"):
            continue
        text = path.read_text(errors="replace") + "\n" + "\n".join(injected.get(rel, []))
        found.extend(violations(rel, text))
        if module_of(rel) in NAMES_NO_DRIVER:
            found.extend(driver_name_comparisons(rel, text, driver_names(root)))
    for header in PURE_CODECS + SEAM + SHARED_TRANSPORTS:
        if not (root / header).exists():
            found.append(f"{header}: listed in tools/check_layering.py, not in the tree")
    for line in found:
        print(line)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
