// Naghshtabrizi and Hespanha's matrix inequalities for a virtual coupling (P. Naghshtabrizi and
// J. P. Hespanha, "Designing Transparent Stabilizing Haptic Controllers", American Control
// Conference, 2006), for controllers of their form (13), C = C_bar + d z/(z-1) + D_c, with
// C_bar strictly proper in controllable canonical form (its denominator alpha and numerator c
// are the unknowns chi) and nu = (d, D_c) fixed:
//   (21) the weighted admittance error ||W (H - E)||^2 < gamma (their (17), by Lemma 1),
//   (22) Theorem 1: (z-1)/(Tz) (C - T/(2b)) strictly positive real (their (18), by Lemma 1),
//   and, beyond the paper, the passivity bound of Roberts, Moore and Colgate that the gate
//   decides by, with the loop's delay: Re{1 + T z^-d H / (b_allowed (z - 1))} > 0, written like
//   (22) for the closed loop,
// each with its pair X = Y^-1 relaxed to [X I; I Y] >= 0 (their (24)). Everything is in
// normalised units (force / position scaled by s) so the solver sees numbers near one; see
// docs/math.md. Not RT-safe.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <vector>

#include "analysis/lmi.h"
#include "analysis/state_space.h"
#include "analysis/transfer_function.h"

namespace hapticd::analysis {

// What the design is given, in the user's units.
struct CouplingSpec {
  TransferFunction environment;  // E(z)
  TransferFunction weight;       // W(z) of the transparency measure
  double sample_period = 0.0;    // T (s)
  double device_damping = 0.0;   // b (N s/m): Theorem 1's
  double allowed_damping = 0.0;  // the most b_req may be: (1 - margin) b - eta (N s/m)
  int delay_samples = 0;         // d of the passivity bound
  int order = 3;                 // degree of C(z); C_bar has order - 1 states
};

// nu of (13), in the user's units: the integrator d z/(z-1) and the feed-through D_c (m/N).
struct CouplingFamily {
  double d = 0.0;
  double dc = 0.0;
};

// chi: C_bar(z) = (c1 z^-1 + ... + cn z^-n) / (1 + a1 z^-1 + ... + an z^-n), normalised
// (multiply by 1/s for m/N).
struct CouplingParameters {
  Eigen::VectorXd alpha;
  Eigen::VectorXd c;
};

// The units the LMIs are written in: force per position in s = E's largest gain on the unit
// circle (N/m), and the weighted error in omega = 1 / max |W E / s|, so that the matrices,
// gamma_hat = gamma (omega / s)^2 and the feasible X and Y all sit near one.
struct CouplingScales {
  double force = 1.0;
  double weight = 1.0;
  double gamma_hat(double gamma) const { return gamma * (weight / force) * (weight / force); }
};
CouplingScales coupling_scales(const CouplingSpec& spec);

// C(z) in the user's units.
TransferFunction coupling_filter_of(const CouplingScales& scales, const CouplingFamily& nu,
                                    const CouplingParameters& chi);

// The generalised plants of Fig. 3: inputs (w, u), outputs (z, y) with y the force into C_bar.
struct CouplingPlants {
  StateSpace transparency;  // z = W (H_hat - E_hat) before closing C_bar
  StateSpace passivity;     // z = T s z^-d H_hat / (b_allowed (z - 1))
};
CouplingPlants coupling_plants(const CouplingSpec& spec, const CouplingScales& scales,
                               const CouplingFamily& nu);

// A system whose matrices are affine in chi.
struct AffineSystem {
  AffineMatrix a, b, c, d;
};

struct MatrixPair {  // X and Y of one of Lemma 1's pairs
  AffineMatrix x;
  AffineMatrix y;
};

struct CouplingLmis {
  int variables = 0;
  std::vector<int> alpha;  // variable index of each alpha_i, then of each c_i
  std::vector<int> c;
  std::array<MatrixPair, 3> pairs;  // transparency (21), Theorem 1 (22), passivity
  // Their systems: the closed loop from w to W (H - E); (z-1)/(Tz)(C - T/(2b)); the closed
  // loop whose real part the passivity bound needs positive.
  std::array<AffineSystem, 3> systems;
  // (21) without its gamma I; gamma's place on the diagonal.
  LmiBlock transparency;
  int gamma_row = 0;
  LmiBlock theorem1;
  LmiBlock passivity;
  std::array<LmiBlock, 3> couplings;  // [X I; I Y] >= 0 for each pair
};

CouplingLmis coupling_lmis(const CouplingSpec& spec, const CouplingScales& scales,
                           const CouplingFamily& nu);

// The problem with (21) at gamma_hat (CouplingScales::gamma_hat) and objective c.
SdpProblem coupling_sdp(const CouplingLmis& lmis, double gamma_hat, const Eigen::VectorXd& c);

CouplingParameters parameters_at(const CouplingLmis& lmis, const Eigen::VectorXd& y);

}  // namespace hapticd::analysis
