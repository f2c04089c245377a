// The linear pieces of docs/math.md as transfer functions: the environment filter E(z) of the
// virtual wall, the contact map H = E / (1 + E C) with the virtual coupling, and the ZOH
// discretisation G(z) of the device with an operator model (for the oscillation check).
#pragma once

#include <optional>

#include "analysis/transfer_function.h"

namespace hapticd::analysis {

enum class WallDiscretization { kBackward, kTustin };

struct WallParams {
  double stiffness = 0.0;       // K (N/m)
  double damping = 0.0;         // B (N s/m)
  double sample_period = 1e-3;  // T (s)
  WallDiscretization discretization = WallDiscretization::kBackward;
};

// backward: E = K + B (1 - z^-1) / T;  Tustin: E = K + (2B/T) (1 - z^-1) / (1 + z^-1).
TransferFunction environment_filter(const WallParams& wall);

// H = E / (1 + E C) in contact; H = E without coupling.
TransferFunction contact_map(const TransferFunction& environment,
                             const std::optional<TransferFunction>& coupling);

// Exact zero-order-hold discretisation of 1 / (m s^2 + c s + k) with c = b + b_h and
// k = k_h: the device (mass m, damping b) pressed by an operator spring k_h and damper b_h,
// from held force to sampled position.
TransferFunction device_operator_zoh(double mass, double damping, double operator_stiffness,
                                     double operator_damping, double sample_period);

}  // namespace hapticd::analysis
