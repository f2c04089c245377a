// The simulated evdev device's half of the evdev driver's registration
// (sim/peers/peer_entry.h): the device on the driver's socketpair. It has no kernel endpoint
// of its own: in the kernel test machine a uinput device written from the kernel's uinput
// documentation stands in (tests/reference/evdev/), and the simulated HID PID device behind
// hid-pidff.
#pragma once

#include "sim/peers/peer_entry.h"

namespace hapticd::sim::evdev {

PeerEntry peer_entry();

}  // namespace hapticd::sim::evdev
