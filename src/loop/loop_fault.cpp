#include "loop/loop_fault.h"

#include <cstdio>

#include "kinematics/pose.h"

namespace hapticd::loop {

std::string describe(const Fault& f) {
  char buf[320];
  const auto tick = static_cast<unsigned long long>(f.tick);
  switch (f.cause) {
    case FaultCause::kNone:
      return "";
    case FaultCause::kTransportRead:
      std::snprintf(buf, sizeof buf, "transport fault reading the device at tick %llu", tick);
      break;
    case FaultCause::kTransportWrite:
      std::snprintf(buf, sizeof buf, "transport fault writing the device at tick %llu", tick);
      break;
    case FaultCause::kDeviceReported:
      std::snprintf(buf, sizeof buf, "the device reported a fault at tick %llu", tick);
      break;
    case FaultCause::kStaleData:
      std::snprintf(buf, sizeof buf,
                    "stale encoder data: no new position for %.0f ticks (tick %llu; "
                    "safety.stale_fault_ticks)",
                    f.value, tick);
      break;
    case FaultCause::kSequenceGap:
      std::snprintf(buf, sizeof buf,
                    "the device's sequence skipped %.0f samples before tick %llu "
                    "(safety.sequence_gap_fault)",
                    f.value, tick);
      break;
    case FaultCause::kNonFinitePosition:
      std::snprintf(buf, sizeof buf, "impossible encoder data: non-finite position at tick %llu",
                    tick);
      break;
    case FaultCause::kEncoderJump:
      std::snprintf(buf, sizeof buf,
                    "impossible encoder data: position jumped at %.6g m/s at tick %llu "
                    "(safety.max_speed)",
                    f.value, tick);
      break;
    case FaultCause::kOverrunStreak:
      std::snprintf(buf, sizeof buf,
                    "%.0f consecutive overruns at tick %llu (loop.overrun_fault_streak)", f.value,
                    tick);
      break;
    case FaultCause::kNonFiniteForce:
      std::snprintf(buf, sizeof buf,
                    "the controller computed a non-finite force (%g) at tick %llu; zero was "
                    "commanded instead",
                    f.value, tick);
      break;
    case FaultCause::kRunaway:
      std::snprintf(buf, sizeof buf,
                    "the wall is not holding: penetration %.4g m at tick %llu and not slowing with "
                    "the force at device.max_force, beyond the %.4g m the wall can hold "
                    "(safety.max_penetration): a reversed force (a wall that pulls) or a device "
                    "too weak for the wall",
                    f.value, tick, f.limit);
      break;
    case FaultCause::kForceReversed:
      std::snprintf(buf, sizeof buf,
                    "the direction check found the force reversed at tick %llu: the push moved "
                    "the device against the force commanded (gain %.3g +- %.2g): a wall would pull",
                    tick, f.value, f.limit);
      break;
    case FaultCause::kNoProbeMotion:
      std::snprintf(buf, sizeof buf,
                    "the direction check saw no motion at tick %llu (gain %.3g +- %.2g, under "
                    "safety.direction_check.min_motion): the device is held, blocked or too "
                    "heavy for the push",
                    tick, f.value, f.limit);
      break;
    case FaultCause::kNeverAtRest:
      std::snprintf(buf, sizeof buf,
                    "the direction check found the device never at rest before tick %llu "
                    "(safety.direction_check.rest_timeout_ms): it was being moved",
                    tick);
      break;
    case FaultCause::kPose:
      std::snprintf(buf, sizeof buf,
                    "the device's pose at tick %llu: %s (device.kinematics): zero torque on "
                    "every joint",
                    tick, kinematics::status_name(static_cast<kinematics::Status>(f.value)));
      break;
  }
  return buf;
}

}  // namespace hapticd::loop
