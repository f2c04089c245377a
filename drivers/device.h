// The one seam between control and hardware. The controller never sees a transport; a driver
// never sees the controller. Lifecycle calls run off the RT thread and may throw DeviceError;
// read/write run on the RT thread every tick and never throw, allocate, lock or log.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace hapticd {

// What an RT-side device call achieved. Counting and fault policy belong to the loop.
enum class IoStatus : std::uint8_t {
  kOk,         // read: a fresh position; write: command accepted by the transport
  kNoNewData,  // read: nothing new since the last tick (the loop counts stale ticks)
  kError,      // the transport or the device failed; describe_error() says how
};

struct PositionSample {
  double position = 0.0;            // axis coordinate (m or rad), device frame
  std::uint32_t device_status = 0;  // driver-specific status bits, recorded in the tick log
};

// Thrown by the non-RT lifecycle calls. The service maps it to exit code 4.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Device {
 public:
  virtual ~Device() = default;

  // Not RT-safe. Opens and configures the transport; output stays disabled.
  virtual void configure() = 0;
  // Not RT-safe. Enables the amplifier; the gate has passed before this is called.
  virtual void enable_output() = 0;
  // Not RT-safe, never throws. Commands zero force and disables the amplifier.
  virtual void disable_output() noexcept = 0;

  // RT-safe: called every tick. Newest position; drains whatever the transport queued.
  virtual IoStatus read(PositionSample& out) noexcept = 0;
  // RT-safe: called every tick. Force command (N or N m) in the device frame.
  virtual IoStatus write(double force) noexcept = 0;

  // Whole samples between write() and the force acting on the device; the gate adds it.
  virtual int transport_delay_samples() const noexcept = 0;
  virtual std::string_view name() const noexcept = 0;
  // Not RT-safe. A sentence describing the last kError, for the fault message.
  virtual std::string describe_error() const = 0;

  // Any thread, once the loop has stopped: the force the driver last handed to the hardware
  // and whether the amplifier is enabled, as the run summary reports them.
  virtual double last_command() const noexcept = 0;
  virtual bool output_enabled() const noexcept = 0;
};

}  // namespace hapticd
