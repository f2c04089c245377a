// The HID driver's only door to the operating system: hidapi (hidapi_transport.cpp is the one
// file that includes <hidapi.h>). Both of hidapi's Linux backends can be chosen per
// configuration: hidraw (the kernel's usbhid/hid-generic keep the device; default) and libusb
// (hidapi claims the USB interface itself, for devices a kernel driver would otherwise hold).
// The two Debian libraries (libhidapi-hidraw0, libhidapi-libusb0) export the same unversioned
// symbols, so one process cannot link both: the chosen one is loaded with dlopen(RTLD_LOCAL)
// and its functions looked up, which also finds hid_get_report_descriptor where the installed
// hidapi has it (0.14 and later) and falls back to the kernel's sysfs copy where it has not.
//
// hid_write blocks until the device takes the report (hidraw and libusb both do a synchronous
// transfer), so output reports go through a small queue to a writer thread: the RT thread
// never waits for USB. A full queue is reported to the caller, which counts it.
#pragma once

#include <memory>
#include <vector>

#include "drivers/hid/device_select.h"
#include "drivers/hid/hid_settings.h"
#include "drivers/hid/hid_transport.h"

namespace hapticd::drivers::hid {

// Not RT-safe. What hidapi's `backend` sees attached. Throws DeviceError when the backend's
// library cannot be loaded or initialised.
std::vector<DeviceListing> enumerate_devices(Backend backend);

// Not RT-safe. Opens the one device `settings.select` names through `settings.backend`, reads
// its report descriptor where it can, and starts the writer thread. Throws DeviceError naming
// what failed (no or several matching devices, permissions, the library).
std::unique_ptr<HidTransport> open_hidapi(const HidSettings& settings);

}  // namespace hapticd::drivers::hid
