// The gate's analysis as curves a person can look at (`hapticd curves`, tools/hapticd-plot):
// the Z-width of the configured device, rate, delay and discretisation (the largest passing
// stiffness for each wall damping), and the loop gain L of the oscillation check over the
// unit circle with the Tsai-Colgate and Tsypkin criteria. The same functions as the gate.
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "analysis/passivity.h"
#include "analysis/transfer_function.h"
#include "config/config.h"

namespace hapticd::gate {

struct ZwidthPoint {
  double damping = 0.0;  // wall B (N s/m)
  analysis::StiffnessLimit max_stiffness;
};

// Not RT-safe, pure. `points` values of B from 0 up to where no stiffness passes any more (or
// twice the damping the gate allows, whichever is first), each with the gate's max_stiffness.
std::vector<ZwidthPoint> zwidth_curve(const config::Config& cfg, int device_delay_samples,
                                      int points = 48);

// The loop gain the oscillation check analyses, E (z^-d G + C), for the wall E and the
// coupling C of cfg (G: the device pressed by the operator model, ZOH).
analysis::TransferFunction oscillation_loop(const config::Config& cfg,
                                            const analysis::TransferFunction& environment,
                                            const std::optional<analysis::TransferFunction>& c,
                                            int delay_samples);

// Why the oscillation check does not apply behind a coupling with a pole at z = 1.
inline constexpr const char* kCouplingPoleNote =
    "not applicable: the coupling's pole at z = 1 makes the loop gain unbounded at DC; "
    "Naghshtabrizi and Hespanha's Theorem 1 (the DSPR check) covers oscillation instead";

struct NyquistPoint {
  double theta = 0.0;  // omega T, in (0, pi]
  std::complex<double> l;
};

// Not RT-safe, pure. L(e^{j theta}) on a grid dense near 0 and over (0, pi]; empty, with
// kCouplingPoleNote in `note`, behind a coupling with a pole at z = 1.
std::vector<NyquistPoint> nyquist_curve(const config::Config& cfg, int device_delay_samples,
                                        std::string& note, int points = 800);

}  // namespace hapticd::gate
