// `hapticd verify`: confirms the gate's passivity bound by measurement (Roberts, Moore & Colgate).
// The whole loop — sim device, controller, servo loop in freerun — is driven by an imposed motion
// in contact, x_k = offset + A cos(theta k) with constant velocity inside each period; the
// cycle-averaged power the operator delivers is affine in the device damping b, and its zero
// is the damping below which the device can hand net energy to the operator at that
// frequency. The maximum over frequencies up to Nyquist is the measured b_req.
#pragma once

#include <vector>

#include "config/config.h"

namespace hapticd::verify {

struct SweepPoint {
  double frequency_hz = 0.0;
  double measured_damping = 0.0;  // zero of the operator power at this frequency
};

struct VerifyResult {
  double analytic_required_damping =
      0.0;  // Roberts-Moore-Colgate eq. 45 (eta is not measurable here)
  double analytic_worst_frequency_hz = 0.0;
  double measured_required_damping = 0.0;
  double worst_frequency_hz = 0.0;  // where the measured maximum was found
  double relative_error = 0.0;
  int delay_samples = 0;    // wall + the configured driver's declared delay
  double amplitude = 0.0;   // of the imposed motion (m)
  std::uint64_t ticks = 0;  // simulated ticks in all runs together
  std::vector<SweepPoint> sweep;
  bool agrees = false;  // relative_error <= tolerance
};

inline constexpr double kVerifyTolerance = 1e-3;

// Not RT-safe (builds many loops). `device_delay_samples` is what the configured driver
// declares (wiring/registry.h): the measured loop is the sim with that much more delay.
// Throws std::invalid_argument for a configuration this measurement cannot cover (an infinite
// bound, or a wall that leaves contact), and std::runtime_error if a measurement loop faults.
VerifyResult verify_passivity(const config::Config& cfg, int device_delay_samples);

}  // namespace hapticd::verify
