// Naghshtabrizi and Hespanha's Example 1 as a design specification, shared by the analysis
// tests and the design benchmark: T = 0.02 s, b = 10 N s/m, K = 1000 N/m, B = 20 N s/m, the
// paper's W(z) = (0.1 z + 0.03)/(100 z - 99) made the felt weight from 1 Hz (docs/math.md), no
// margin (config/coupling-example.yaml).
#pragma once

#include "analysis/coupling_design.h"
#include "analysis/transparency_weight.h"
#include "analysis/wall_model.h"

namespace hapticd::testing {

inline analysis::CouplingSpec coupling_example1(int order = 3, int delay = 0) {
  analysis::CouplingSpec s;
  s.environment =
      analysis::environment_filter({1000, 20, 0.02, analysis::WallDiscretization::kBackward});
  s.weight = analysis::felt_weight({{0.1, 0.03}, {100, -99}}, 1.0, 0.02);
  s.sample_period = 0.02;
  s.device_damping = 10;
  s.allowed_damping = 10;
  s.delay_samples = delay;
  s.order = order;
  return s;
}

}  // namespace hapticd::testing
