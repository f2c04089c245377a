// Oscillation-free criteria for a loop with a unilateral nonlinearity (J. C. Tsai and
// J. E. Colgate, "Stability of Discrete Time Systems with Unilateral Nonlinearities", ASME
// International Mechanical Engineering Congress and Exposition, 1995, eq. 25) and Tsypkin's criterion, on the loop gain L(z) seen by xi(.).
// Tsai-Colgate: no limit cycle can exist if for all 0 < theta <= pi, with
// m = sin(theta) / (1 - cos(theta)):  max(Re L + m Im L, Re L - m Im L) > -1.
// Tsypkin: Re L > -1 for all theta.
#pragma once

#include <string>

#include "analysis/transfer_function.h"

namespace hapticd::analysis {

struct OscillationCheck {
  // The paper's standing assumptions: L stable, (1 + L)^-1 stable, L(1) >= 0. When they
  // fail the criteria say nothing and `applicable` is false with the reason in `note`.
  bool applicable = false;
  std::string note;
  bool tsai_colgate = false;
  bool tsypkin = false;
  double tsai_colgate_margin = 0.0;  // min over theta of max(...) + 1; > 0 passes
  double tsypkin_margin = 0.0;       // min over theta of Re L + 1; > 0 passes
  double worst_theta = 0.0;          // where the Tsai-Colgate margin is smallest
};

OscillationCheck oscillation_check(const TransferFunction& loop);

}  // namespace hapticd::analysis
