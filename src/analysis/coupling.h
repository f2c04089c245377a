// The virtual-coupling checks of P. Naghshtabrizi and J. P. Hespanha, "Designing Transparent
// Stabilizing Haptic Controllers", American Control Conference, 2006: Theorem 1's condition
// that (z - 1)/(T z) (C(z) - T/(2b)) is discrete-time strictly positive real, the
// transparency gamma = max |W (H - E)|^2, and the static stiffness H(1) a user feels under a
// steady push.
#pragma once

#include <optional>
#include <string>

#include "analysis/frequency_search.h"
#include "analysis/transfer_function.h"

namespace hapticd::analysis {

struct CouplingCheck {
  bool admissible = false;  // C stable but for at most a simple pole at z = 1
  bool pole_at_one = false;
  bool dspr = false;
  double dspr_min_real = 0.0;  // min over the circle of Re{(z-1)/(Tz)(C - T/(2b))}
  double dspr_worst_theta = 0.0;
  std::string note;  // why it fails, when it does
};

CouplingCheck coupling_check(const TransferFunction& coupling, double sample_period,
                             double device_damping);

// gamma = max over theta of |W (H - E)|^2; +inf when H - E is unbounded on the circle.
Extremum transparency_gamma(const TransferFunction& contact_map,
                            const TransferFunction& environment, const TransferFunction& weight);

// H(1) with H = E / (1 + E C): 0 when C has a pole at z = 1 (the coupling yields under a
// steady push), E(1) / (1 + E(1) C(1)) otherwise.
double static_stiffness(const TransferFunction& environment,
                        const std::optional<TransferFunction>& coupling);

}  // namespace hapticd::analysis
