#include "drivers/device.h"

#include <algorithm>
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
    if (info_.joints < 1 || info_.joints > base::kMaxJoints) {
      throw DeviceError(std::string(driver_name()) + ": the device declares " +
                        std::to_string(info_.joints) + " joints; hapticd drives 1 to " +
                        std::to_string(base::kMaxJoints));
    }
  } catch (...) {
    on_close();  // whatever was opened before the failure
    throw;
  }
  fault_ = {};
  refusal_ = Refusal::kNone;
  clear_commands();
  state_.store(DeviceState::kConfigured, std::memory_order_release);
}

void Device::enable() {
  require(DeviceState::kConfigured, "enable()");
  try {
    on_enable();
  } catch (...) {
    on_disable();  // undo a half-done enable: never leave an amplifier half on
    clear_commands();
    throw;
  }
  clear_commands();
  state_.store(DeviceState::kActive, std::memory_order_release);
}

void Device::disable() noexcept {
  const DeviceState s = state();
  if (s != DeviceState::kActive && s != DeviceState::kFaulted) return;
  on_disable();
  clear_commands();
  if (s == DeviceState::kActive) state_.store(DeviceState::kConfigured, std::memory_order_release);
}

void Device::clear_fault() {
  require(DeviceState::kFaulted, "clear_fault()");
  on_disable();
  on_clear_fault();
  fault_ = {};
  refusal_ = Refusal::kNone;
  state_.store(DeviceState::kConfigured, std::memory_order_release);
}

void Device::close() noexcept {
  const DeviceState s = state();
  if (s == DeviceState::kUnconfigured) return;
  if (s == DeviceState::kActive || s == DeviceState::kFaulted) on_disable();
  on_close();
  clear_commands();
  state_.store(DeviceState::kUnconfigured, std::memory_order_release);
}

std::string Device::describe_fault() const {
  if (fault_.fault_class == FaultClass::kNone) return std::string(driver_name()) + ": no fault";
  if (refusal_ == Refusal::kNonFinite) {
    return std::string(driver_name()) + ": a non-finite force command was refused; zero written";
  }
  if (refusal_ == Refusal::kJointCount) {
    return std::string(driver_name()) + ": a read or write for another number of joints than the " +
           std::to_string(info_.joints) + " the device has was refused; zero written";
  }
  return describe(fault_);
}

void Device::clear_commands() noexcept {
  for (auto& c : last_command_) c.store(0.0, std::memory_order_relaxed);
}

void Device::write_zero() noexcept {
  static constexpr std::array<double, base::kMaxJoints> kZero{};
  on_write(std::span<const double>(kZero.data(), info_.joints));
}

IoStatus Device::latch(IoStatus status) noexcept {
  fault_ = {status == IoStatus::kDeviceFault ? FaultClass::kDevice : FaultClass::kTransport,
            pending_code_};
  pending_code_ = 0;
  state_.store(DeviceState::kFaulted, std::memory_order_release);
  write_zero();  // zero force at once, best effort: the transport may be what failed
  clear_commands();
  return status;
}

IoStatus Device::refuse(Refusal why) noexcept {
  refusal_ = why;
  return latch(IoStatus::kTransportFault);
}

IoStatus Device::read(std::span<PositionSample> out, std::uint32_t periods) noexcept {
  const DeviceState s = state();
  if (s != DeviceState::kActive && s != DeviceState::kConfigured) {
    return s == DeviceState::kFaulted && fault_.fault_class == FaultClass::kDevice
               ? IoStatus::kDeviceFault
               : IoStatus::kTransportFault;
  }
  if (out.size() != info_.joints) return refuse(Refusal::kJointCount);
  read_periods_ = std::max<std::uint32_t>(periods, 1);
  const IoStatus r = on_read(out);
  if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return latch(r);
  return r;
}

IoStatus Device::write(std::span<const double> forces) noexcept {
  const DeviceState s = state();
  if (s == DeviceState::kFaulted) {
    write_zero();  // a latched fault passes nothing but zero
    return fault_.fault_class == FaultClass::kDevice ? IoStatus::kDeviceFault
                                                     : IoStatus::kTransportFault;
  }
  if (s != DeviceState::kActive) return IoStatus::kTransportFault;
  if (forces.size() != info_.joints) return refuse(Refusal::kJointCount);
  for (const double f : forces) {  // whatever the caller: never hand a NaN to an amplifier
    if (!std::isfinite(f)) return refuse(Refusal::kNonFinite);
  }
  const IoStatus r = on_write(forces);
  if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return latch(r);
  for (std::size_t j = 0; j < forces.size(); ++j) {
    last_command_[j].store(forces[j], std::memory_order_relaxed);
  }
  return r;
}

}  // namespace hapticd
