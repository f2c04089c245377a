#include "drivers/device.h"

#include <cmath>

namespace hapticd {

std::string_view to_string(DeviceState state) noexcept {
  switch (state) {
    case DeviceState::kUnconfigured:
      return "unconfigured";
    case DeviceState::kConfigured:
      return "configured";
    case DeviceState::kActive:
      return "active";
    case DeviceState::kFaulted:
      return "faulted";
  }
  return "unknown";
}

void Device::require(DeviceState expected, const char* call) const {
  const DeviceState s = state();
  if (s != expected) {
    throw DeviceError(std::string(driver_name()) + ": " + call + " is not allowed while " +
                      std::string(to_string(s)) + " (it needs " + std::string(to_string(expected)) +
                      ")");
  }
}

void Device::configure() {
  require(DeviceState::kUnconfigured, "configure()");
  try {
    info_ = on_configure();
  } catch (...) {
    on_close();  // whatever was opened before the failure
    throw;
  }
  fault_ = {};
  non_finite_command_ = false;
  last_command_.store(0.0, std::memory_order_relaxed);
  state_.store(DeviceState::kConfigured, std::memory_order_release);
}

void Device::enable() {
  require(DeviceState::kConfigured, "enable()");
  try {
    on_enable();
  } catch (...) {
    on_disable();  // undo a half-done enable: never leave an amplifier half on
    last_command_.store(0.0, std::memory_order_relaxed);
    throw;
  }
  last_command_.store(0.0, std::memory_order_relaxed);
  state_.store(DeviceState::kActive, std::memory_order_release);
}

void Device::disable() noexcept {
  const DeviceState s = state();
  if (s != DeviceState::kActive && s != DeviceState::kFaulted) return;
  on_disable();
  last_command_.store(0.0, std::memory_order_relaxed);
  if (s == DeviceState::kActive) state_.store(DeviceState::kConfigured, std::memory_order_release);
}

void Device::clear_fault() {
  require(DeviceState::kFaulted, "clear_fault()");
  on_disable();
  on_clear_fault();
  fault_ = {};
  non_finite_command_ = false;
  state_.store(DeviceState::kConfigured, std::memory_order_release);
}

void Device::close() noexcept {
  const DeviceState s = state();
  if (s == DeviceState::kUnconfigured) return;
  if (s == DeviceState::kActive || s == DeviceState::kFaulted) on_disable();
  on_close();
  last_command_.store(0.0, std::memory_order_relaxed);
  state_.store(DeviceState::kUnconfigured, std::memory_order_release);
}

std::string Device::describe_fault() const {
  if (fault_.fault_class == FaultClass::kNone) return std::string(driver_name()) + ": no fault";
  if (non_finite_command_) {
    return std::string(driver_name()) + ": a non-finite force command was refused; zero written";
  }
  return describe(fault_);
}

IoStatus Device::latch(IoStatus status) noexcept {
  fault_ = {status == IoStatus::kDeviceFault ? FaultClass::kDevice : FaultClass::kTransport,
            pending_code_};
  pending_code_ = 0;
  state_.store(DeviceState::kFaulted, std::memory_order_release);
  on_write(0.0);  // zero force at once, best effort: the transport may be what failed
  last_command_.store(0.0, std::memory_order_relaxed);
  return status;
}

IoStatus Device::read(PositionSample& out) noexcept {
  const DeviceState s = state();
  if (s != DeviceState::kActive && s != DeviceState::kConfigured) {
    return s == DeviceState::kFaulted && fault_.fault_class == FaultClass::kDevice
               ? IoStatus::kDeviceFault
               : IoStatus::kTransportFault;
  }
  const IoStatus r = on_read(out);
  if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return latch(r);
  return r;
}

IoStatus Device::write(double force) noexcept {
  const DeviceState s = state();
  if (s == DeviceState::kFaulted) {
    on_write(0.0);  // a latched fault passes nothing but zero
    return fault_.fault_class == FaultClass::kDevice ? IoStatus::kDeviceFault
                                                     : IoStatus::kTransportFault;
  }
  if (s != DeviceState::kActive) return IoStatus::kTransportFault;
  if (!std::isfinite(force)) {  // whatever the caller: never hand a NaN to an amplifier
    non_finite_command_ = true;
    return latch(IoStatus::kTransportFault);
  }
  const IoStatus r = on_write(force);
  if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return latch(r);
  last_command_.store(force, std::memory_order_relaxed);
  return r;
}

}  // namespace hapticd
