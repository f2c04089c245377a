// `hapticd verify` for a device of several joints (docs/math.md, the gate over a workspace): each
// wall measured on the simulated multi-joint loop at the configuration the gate found worst for
// it. An operator imposes the motion that dissipates least for the normal velocity it makes,
// x_k = x* + d A cos(theta k) with d = b_n J B_j^-1 J^T n (so n . d = 1: the joints move as
// q' = b_n B_j^-1 J^T n v_n, which dissipates b_n v_n^2), while the servo loop, the kinematics
// and the wall's law along n (control/scene.h, loop/scene_tick.h) command the joints. Over whole
// periods the operator's work is what the joints dissipate, sum q'^T B_j q' T, less what the
// torques do, sum tau_k . (q_{k+1} - q_k) (exact for torques held over each period): its zero,
// b = sum tau . dq / sum ds^2 / T, is the damping along n below which the loop hands the
// operator energy at that frequency, and its largest over frequencies is the measured b_req.
// The device is active at x* when that exceeds the damping the motion met there (b_n).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "config/config.h"
#include "kinematics/pose.h"
#include "verify/passivity_sweep.h"

namespace hapticd::verify {

struct WallVerify {
  kinematics::Vec3 position = kinematics::Vec3::Zero();  // x*, where it is measured (m)
  double analytic_required_damping = 0.0;  // the one-axis bound along n (eta not measurable)
  double measured_required_damping = 0.0;  // the largest zero over frequencies
  double worst_frequency_hz = 0.0;
  double relative_error = 0.0;
  double normal_damping = 0.0;           // b_n at x*, as the gate computes it
  double measured_normal_damping = 0.0;  // what the joints dissipated per ds^2 / T there
  bool measured_passive = false;         // measured b_req <= measured b_n: passive at x*
  bool agrees = false;                   // relative_error <= kVerifyTolerance
  std::vector<SweepPoint> sweep;
  std::uint64_t ticks = 0;
};

struct WorkspaceVerifyResult {
  std::vector<WallVerify> walls;  // one per cfg.walls entry
  double amplitude = 0.0;         // A (m)
  int device_delay_samples = 0;   // the configured driver's, on every wall's own
  bool agrees = false;            // every wall's
};

// Not RT-safe (builds many loops). `worst` holds each wall's x* (the gate's worst position,
// gate/workspace_gate.h); `device_delay_samples` what the configured driver declares. Throws
// std::invalid_argument for a wall whose bound is infinite, whose x* is not a pose or where
// the device cannot move along its normal, std::runtime_error if a measurement loop faults.
WorkspaceVerifyResult verify_workspace(const config::Config& cfg, int device_delay_samples,
                                       std::span<const kinematics::Vec3> worst);

}  // namespace hapticd::verify
