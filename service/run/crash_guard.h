// What can still be done when the process crashes (SIGSEGV, SIGBUS, SIGFPE, SIGILL, or an
// abort()): write the device's prebuilt zero-force and disable messages (Device::
// emergency_stop(), async-signal-safe), then let the signal end the process as it would have.
// The drive's own watchdog is the second line (docs/devices.md). A stack overflow is not
// covered: the handler has no stack of its own to run on.
#pragma once

#include "drivers/device.h"

namespace hapticd::service {

// Not RT-safe. Installs the crash handlers (once) and makes `device` the one they stop;
// nullptr: none. Call with the device once it is configured, and with nullptr before it is
// closed or destroyed.
void guard_device_on_crash(Device* device) noexcept;

// RAII form: guards `device` for its lifetime.
class CrashGuard {
 public:
  explicit CrashGuard(Device& device) noexcept { guard_device_on_crash(&device); }
  ~CrashGuard() { guard_device_on_crash(nullptr); }
  CrashGuard(const CrashGuard&) = delete;
  CrashGuard& operator=(const CrashGuard&) = delete;
};

}  // namespace hapticd::service
