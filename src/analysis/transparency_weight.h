// The weights of the transparency measure gamma = max |W (H - E)|^2 (docs/math.md).
//
// Theorem 1 of Naghshtabrizi and Hespanha forces a pole of C(z) at z = 1, so every admissible
// coupling has H(1) = 0 and max |W (H - E)|^2 >= |W(1) E(1)|^2: with a weight that does not
// vanish at DC (theirs, W = (0.1 z + 0.03)/(100 z - 99), gives (0.13 x 1000)^2 = 16 900 for
// Example 1) the measure is the same floor for every admissible C and ranks nothing. The felt
// weight keeps the configured W from f_c up and removes what no coupling can change: it is W
// times a second-order high-pass at f_c, so below f_c (a steady push, where the coupled wall
// creeps at d/T per newton, reported on its own) it falls off as f^2.
#pragma once

#include "analysis/transfer_function.h"

namespace hapticd::analysis {

// W (z) ((1 + p)/2)^2 (1 - z^-1)^2 / (1 - p z^-1)^2 with p = exp(-2 pi f_c T): unit gain at
// the Nyquist frequency, zero at DC. Throws std::invalid_argument unless 0 < f_c < 1/(2T).
TransferFunction felt_weight(const TransferFunction& weight, double felt_from_hz,
                             double sample_period);

}  // namespace hapticd::analysis
