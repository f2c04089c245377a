// The Falcon driver's door to the device: libusb (usb_link.cpp is the one file that includes
// <libusb.h>). The FT232 is claimed whole (interface 0; a kernel driver bound to it, ftdi_sio,
// is detached while hapticd holds it and given back after). The load and homing use libusb's
// synchronous calls; from start() on, two threads of their own carry the ticks: a writer that
// sends the newest packet the RT thread left (an eventfd wakes it) and a reader that keeps a bulk
// IN transfer waiting and passes each one's data, its modem status bytes dropped, through a ring
// the RT thread drains. The RT thread never waits for USB and never calls libusb (a transfer's
// submission allocates). libusb drives a descriptor of the device's usbfs node opened here, on
// which a crash handler can write the zero packet with one ioctl (libusb is not
// async-signal-safe).
#pragma once

#include <memory>
#include <string>

#include "drivers/falcon/falcon_settings.h"
#include "drivers/falcon/falcon_transport.h"

namespace hapticd::drivers::falcon {

// Not RT-safe. Opens the one Falcon `s.serial` names (any, when empty and only one is
// attached). Throws DeviceError naming what failed: none or several attached, no permission
// (with the udev rule's command), the interface busy.
std::unique_ptr<FalconTransport> open_usb(const FalconSettings& s, int output_priority);

// Not RT-safe. The Falcons attached, each with the key that selects it, for `hapticd devices`;
// what libusb could not do said in the text.
std::string list_falcons();

}  // namespace hapticd::drivers::falcon
