// Why the servo loop stopped driving the motor. A fault commands zero force at once, latches
// and ends the loop; the service disables output and reports the cause.
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::loop {

enum class FaultCause : std::uint8_t {
  kNone,
  kDeviceRead,   // Device::read returned kError
  kDeviceWrite,  // Device::write returned kError
  kStaleData,    // no new position for safety.stale_fault_ticks ticks in a row
  kNonFinitePosition,
  kEncoderJump,     // |x_k - x_{k-1}| / T above safety.max_speed
  kOverrunStreak,   // loop.overrun_fault_streak consecutive overruns
  kNonFiniteForce,  // the controller computed a NaN or infinite force (zero was commanded)
};

struct Fault {
  FaultCause cause = FaultCause::kNone;
  std::uint64_t tick = 0;
  double value = 0.0;  // the offending number (speed, streak length, ...), cause-specific
};

// Not RT-safe. One sentence naming the cause, the tick and the number.
std::string describe(const Fault& f);

}  // namespace hapticd::loop
