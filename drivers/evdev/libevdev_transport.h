// The evdev driver's only door to the operating system: an input device node
// (/dev/input/eventN) through libevdev (libevdev_transport.cpp is the one file that includes
// <libevdev/libevdev.h>). libevdev keeps the device's state and, when the kernel's buffer
// overflowed (SYN_DROPPED), reads it again so the axis is never left at a value the device no
// longer has. The force goes through the kernel's force-feedback interface, which libevdev
// does not wrap: EVIOCSFF and EVIOCRMFF ioctls, and EV_FF events written to the node.
#pragma once

#include <memory>
#include <vector>

#include "drivers/evdev/device_select.h"
#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_transport.h"

namespace hapticd::drivers::evdev {

struct Enumeration {
  std::vector<InputListing> devices;  // every /dev/input/eventN that could be opened
  int unreadable = 0;                 // those that could not (permissions)
};

// Not RT-safe. What /dev/input holds, each node with its by-id and by-path links.
Enumeration enumerate_input_devices();

// Not RT-safe. Opens the one device `settings.select` names (read and write: the force is
// written to it), with its event times on CLOCK_MONOTONIC. Throws DeviceError naming what
// failed (no or several matching devices, permissions). `listing` receives what was opened.
std::unique_ptr<EvdevTransport> open_libevdev(const EvdevSettings& settings, InputListing& listing);

}  // namespace hapticd::drivers::evdev
