// Everything the per-tick controller needs, resolved from the configuration once, off the RT
// thread: normalised filter coefficients and the cached constants of docs/math.md, so the
// tick multiplies and never divides.
#pragma once

#include <array>
#include <cstddef>

#include <optional>

#include "analysis/transfer_function.h"
#include "analysis/wall_model.h"
#include "config/config.h"

namespace hapticd::control {

inline constexpr std::size_t kMaxTaps = config::kMaxCouplingCoefficients;  // per polynomial

// A causal IIR filter num(z^-1)/den(z^-1) with den[0] normalised to 1.
struct FilterCoefficients {
  std::array<double, kMaxTaps> num{};
  std::array<double, kMaxTaps> den{};  // den[0] == 1
  std::size_t num_taps = 1;
  std::size_t den_taps = 1;
};

struct ControlLaw {
  double wall_position = 0.0;      // x0
  double normal = 1.0;             // n
  FilterCoefficients environment;  // E(z)
  bool has_coupling = false;
  FilterCoefficients coupling;  // C(z)
  int delay_samples = 0;        // d: f_{k-d} is commanded at tick k
  bool no_pull = false;
  // The wall acts only once the device has been seen outside it: a device that starts inside
  // gets zero force (not K p0 + B p0 / T at once) until it leaves. `verify` turns this off to
  // measure the linear law from an imposed motion that starts in contact.
  bool require_outside_start = true;
  // The linear law the passivity bound is about: the contact never opens (xi = the proxy
  // penetration, negative or not). Only `verify`'s measurement sets it: behind a coupling with
  // a pole at z = 1 the mean force of any bounded motion decays to zero (H(1) = 0), so the
  // unilateral wall would leave contact and the loop measured would not be linear.
  bool linear_contact = false;
  double max_force = 0.0;
  // The runaway guard: a penetration beyond this while the wall pushes at max_force faults
  // (safety.max_penetration, or kRunawayMargin max_force / K; infinite for K = 0 and none set).
  double runaway_penetration = 0.0;
  double sample_period = 0.0;
  // Cached derived constants.
  double inv_sample_period = 0.0;
  double e0 = 0.0;                 // E's direct feed-through
  double c0 = 0.0;                 // C's direct feed-through
  double inv_one_plus_e0c0 = 1.0;  // 1 / (1 + e0 c0)
};

// The configured wall as the analysis sees it, at stiffness `stiffness` (the gate varies it
// to find the largest that passes), and the configured coupling C(z), if any. The controller,
// the gate and `verify` all build their models from these, so they analyse what runs.
analysis::WallParams wall_params(const config::Config& cfg, double stiffness);
std::optional<analysis::TransferFunction> coupling_filter(const config::Config& cfg);

// Not RT-safe, pure. The runaway guard's bound for `cfg` (ControlLaw::runaway_penetration).
double runaway_penetration(const config::Config& cfg);

// Not RT-safe. Throws std::invalid_argument for a law the controller cannot run
// (too many coefficients, negative feed-through).
ControlLaw make_control_law(const config::Config& cfg);

}  // namespace hapticd::control
