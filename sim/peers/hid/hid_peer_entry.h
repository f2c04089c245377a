// The simulated HID device's half of the HID driver's registration (sim/peers/peer_entry.h):
// the firmware of device.hid's profile on the driver's socketpair, or on a USB HID gadget, a
// raw USB gadget or uhid (`hapticd peer --endpoint /dev/hidgN`).
#pragma once

#include "sim/peers/peer_entry.h"

namespace hapticd::sim::hid {

PeerEntry peer_entry();

}  // namespace hapticd::sim::hid
