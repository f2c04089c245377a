// The GPIO driver's transport seam: everything the Device needs from the outside world, so the
// same driver code runs against the kernel (libgpiod lines and sysfs PWM, KernelTransport)
// or against its simulated peer over a SOCK_SEQPACKET pair (LoopbackTransport, gpio_wire.h).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>

#include "base/joints.h"
#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/quadrature_decoder.h"

namespace hapticd::drivers::gpio {

// The lines' raw levels (wire::kLevel* bits) of each joint, joint i at [i].
using JointLevels = std::array<std::uint8_t, base::kMaxJoints>;

// What one read of the edge streams (every chip's) found.
struct EdgeRead {
  std::size_t count = 0;  // edges written to the buffer, each joint's oldest first; raw levels
  // The time up to which the stream is complete (no earlier edge is still to come): the read
  // time for the kernel, the peer's clock for the loopback. 0: the stream's clock did not
  // advance (the loopback peer sent nothing).
  std::int64_t complete_until_ns = 0;
  // Each joint's events the transport knows it lost (sequence numbers skipped).
  std::array<std::uint64_t, base::kMaxJoints> lost{};
  int error = 0;                 // an errno: the transport failed (the edges read are still valid)
  std::uint8_t error_joint = 0;  // a joint whose lines failed (the first on the failed chip)
};

// The output is written whole every tick; a transport passes on only what changed (the kernel
// transport: one sysfs write or line ioctl per changed value) or what its peer needs.
using OutputState = wire::Output;

class GpioTransport {
 public:
  virtual ~GpioTransport() = default;

  // Not RT-safe. Opens everything with each joint's output at off[joint] (off.size() joints);
  // returns every joint's raw levels. Throws DeviceError naming what could not be opened and
  // why.
  virtual JointLevels open(std::span<const OutputState> off) = 0;
  // Not RT-safe. Releases everything; the output is left as the last write left it.
  virtual void close() noexcept = 0;
  // Not RT-safe. Every joint's raw levels now (clear_fault checks the fault lines).
  virtual JointLevels read_levels() = 0;
  // One line for the device description ("gpiochip0 [pinctrl] lines 17,27 pwmchip0/pwm0").
  virtual std::string describe() const = 0;

  // RT-safe: called every tick. Every pending edge of every joint (Edge::joint says whose),
  // without blocking, up to buffer.size().
  virtual EdgeRead read_edges(std::span<Edge> buffer) noexcept = 0;
  // RT-safe: called every tick for each joint, in joint order. out.joint's duty and direction;
  // 0 or the errno of the write that failed.
  virtual int write_output(const OutputState& out) noexcept = 0;
  // Async-signal-safe: zero duty on every joint through already-open descriptors, nothing
  // else.
  virtual void emergency_stop() noexcept = 0;
};

// Event sequence numbers (the 2.x API's and the loopback's, 32-bit here): how many were
// skipped since the last one seen.
class SequenceCheck {
 public:
  std::uint64_t next(std::uint32_t seqno) noexcept {
    const std::uint32_t gap = have_ ? seqno - expected_ : 0;  // wraps with the counter
    expected_ = seqno + 1;
    have_ = true;
    // A number from the past (half the range back or more): reordered or repeated, not 4e9
    // events lost; it still means the stream cannot be trusted, so it counts as one.
    return gap >= 0x8000'0000u ? 1 : gap;
  }
  void reset() noexcept { have_ = false; }

 private:
  std::uint32_t expected_ = 0;
  bool have_ = false;
};

}  // namespace hapticd::drivers::gpio
