// The kernel's copy of a HID device's report descriptor (sysfs), for a hidapi without
// hid_get_report_descriptor (it arrived in 0.14; Debian 12 has 0.13). Called by
// hidapi_transport.cpp before it opens the device: the libusb backend detaches usbhid, and
// with it the kernel's copy.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace hapticd::drivers::hid {

// Not RT-safe. The descriptor of the device at hidapi path `path`: a hidraw node
// (/dev/hidrawN, under /sys/class/hidraw/hidrawN/device/), or with `libusb_path` a USB
// interface ("1-1:1.0", under the HID device of /sys/bus/usb/devices/1-1:1.0/) while usbhid
// still holds it. Nothing when there is no copy, or it is empty or longer than any descriptor.
std::optional<std::vector<std::uint8_t>> kernel_report_descriptor(const std::string& path,
                                                                  bool libusb_path);

}  // namespace hapticd::drivers::hid
