// `hapticd design-coupling`: Naghshtabrizi and Hespanha's design of the virtual coupling C(z)
// for the configured wall (T, b, K, B, the delay the gate uses), verified by the gate itself
// before it is printed as the `wall.coupling` to paste (docs/math.md).
#pragma once

#include <string>

#include "service/config_source.h"

namespace hapticd::service {

struct DesignCouplingOptions {
  ConfigOptions config;
  int order = 3;                // degree of C(z)
  std::string weight = "felt";  // felt | configured
  double felt_from_hz = 1.0;    // the felt band's lower edge
  int max_steps = 24;           // outer steps
  int max_iterations = 12;      // cone complementarity iterations per step
  bool json = false;
};

// Exit 0: designed and passed by the gate, or none needed (the wall passes the gate bare:
// nothing is designed or printed as a coupling); 1: not converged, no coupling found, or refused by
// the gate's exact check (never printed as a coupling); 2: bad input. One progress line per
// outer step on stderr.
int design_coupling_command(const DesignCouplingOptions& options);

}  // namespace hapticd::service
