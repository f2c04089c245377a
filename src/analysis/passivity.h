// The passivity bound of R. G. Roberts, C. A. Moore and J. E. Colgate, "A New Expression for
// the Passivity Bound for a Class of Sampled-Data Systems", IEEE Transactions on Haptics,
// 2023 (eq. 45 and 54; docs/math.md): the sampled-data
// loop of a device with damping b, ZOH, sampler and environment H(z) delayed by d samples is
// passive against an operator with a shortage of passivity eta iff
//   b > b_req = max_{0 <= theta <= pi} Re{ T H(e^{j theta}) e^{-j theta d} / (1 - e^{j theta}) } +
//   eta.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "analysis/transfer_function.h"
#include "analysis/wall_model.h"

namespace hapticd::analysis {

struct PassivityBound {
  // +inf when no finite damping makes the loop passive (e.g. H unstable).
  double required_damping = 0.0;
  double worst_theta = 0.0;         // rad per sample where the maximum is attained
  double worst_frequency_hz = 0.0;  // worst_theta / (2 pi T)
  std::string note;                 // why the bound is infinite, if it is
};

PassivityBound passivity_bound(const TransferFunction& h, double sample_period, int delay_samples,
                               double passivity_shortage = 0.0);

struct StiffnessLimit {
  enum class Kind {
    kBounded,    // value is the largest K that passes
    kUnbounded,  // every K tried up to value passes (e.g. behind a virtual coupling)
    kNone,       // not even K = 0 passes (value = 0)
  };
  Kind kind = Kind::kBounded;
  double value = 0.0;
};

// Largest stiffness K with b_req(K) <= available_damping, where `make_h(K)` builds the
// contact map for stiffness K. Scans K geometrically, then bisects the last pass-to-fail
// transition to full precision.
StiffnessLimit max_stiffness(const std::function<TransferFunction(double)>& make_h,
                             double sample_period, int delay_samples, double passivity_shortage,
                             double available_damping);

}  // namespace hapticd::analysis
