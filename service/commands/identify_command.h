// `hapticd identify`: with the device held free (no wall), drive it with a multisine force
// within device.max_force, record its positions, and fit its mass m and viscous damping b (and
// Coulomb friction where it fits better) on the exact ZOH model (analysis/free_motion_fit.h):
// the numbers the gate's passivity bound rests on, which users rarely know.
#pragma once

#include <optional>

#include "service/config_source.h"
#include "service/stop_signals.h"

namespace hapticd::service {

// The shape of `identify --json` (docs/operations.md): 1 had no schema_version; 2 added it,
// force_direction and reverse_with (mass and damping are negative when the force is reversed);
// 3 added joint and joints (the joint excited, of how many).
inline constexpr int kIdentifySchemaVersion = 3;

struct IdentifyOptions {
  ConfigOptions config;
  bool json = false;
  bool loopback = false;     // the configured driver against its simulated peer
  bool device_free = false;  // --yes-the-device-is-free: required on a real driver
  // N; default 0.4 device.max_force, less when the configured m and b predict that it would
  // take the device past half of max_travel.
  std::optional<double> amplitude;
  std::optional<double> f_low;   // Hz; default from the configured m and b
  std::optional<double> f_high;  // Hz
  double duration_s = 8.0;
  double max_travel = 0.1;  // m from the start before the excitation stops as a fault
  // --joint: the joint excited, 0-based as device.mass[J] (required for several joints); the
  // others are commanded zero.
  std::optional<int> joint;
};

// Returns the exit code: 0 fitted, 1 a fault during the excitation (zero force, output off) or
// a reversed force (the fit needs a negative mass: reported with the setting that reverses it,
// and no configuration printed), 2 bad input (and a real driver without
// --yes-the-device-is-free), 4 device error.
int identify_command(const IdentifyOptions& options, SignalWatch& signals);

}  // namespace hapticd::service
