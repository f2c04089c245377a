// Why the servo loop stopped driving the motor. A fault commands zero force at once, latches
// and ends the loop; the service disables output and reports the cause.
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::loop {

enum class FaultCause : std::uint8_t {
  kNone,
  kTransportRead,   // Device::read: the transport failed (I/O error, bus-off, device gone)
  kTransportWrite,  // Device::write: the transport failed (or refused the command)
  kDeviceReported,  // the device reported a fault (status bit, EMCY, axis error)
  kStaleData,       // no new position for safety.stale_fault_ticks ticks, or one that old
  kNonFinitePosition,
  kEncoderJump,     // |x_k - x_{k-1}| / dt above safety.max_speed
  kOverrunStreak,   // loop.overrun_fault_streak consecutive overruns
  kNonFiniteForce,  // the controller computed a NaN or infinite force (zero was commanded)
  kSequenceGap,     // the device's sequence skipped safety.sequence_gap_fault samples or more
  // The runaway guard: deeper than safety.max_penetration (value: the penetration, limit: the
  // bound) while the wall pushed at device.max_force: the wall is not holding.
  kRunaway,
  // The direction check (control/direction_probe.h; value: its gain, limit: the gain's
  // standard error): the force is reversed; the device did not move under the pulse; it never
  // came to rest to be tried (the last two only with safety.direction_check.on_no_motion:
  // refuse). The wall was never armed: these refuse the device rather than fault a run.
  kForceReversed,
  kNoProbeMotion,
  kNeverAtRest,
  // A device of several joints whose pose was not ok (value: its kinematics::Status): outside
  // device.kinematics.workspace or no assembly, near a singularity, or no convergence.
  kPose,
};

// Whether the cause is the direction check's refusal (exit 3, as the gate's).
inline bool is_direction_refusal(FaultCause c) noexcept {
  return c == FaultCause::kForceReversed || c == FaultCause::kNoProbeMotion ||
         c == FaultCause::kNeverAtRest;
}

struct Fault {
  FaultCause cause = FaultCause::kNone;
  std::uint64_t tick = 0;
  double value = 0.0;  // the offending number (speed, streak length, gap...), cause-specific
  double limit = 0.0;  // the bound it crossed, where the cause has one (kRunaway, the check's)
};

// Not RT-safe. One sentence naming the cause, the tick and the number. For a device or
// transport fault the device's own description follows it (Device::describe_fault()).
std::string describe(const Fault& f);

}  // namespace hapticd::loop
