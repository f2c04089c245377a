#include "gate/gate.h"

#include <cmath>
#include <numbers>

#include "analysis/coupling.h"
#include "analysis/oscillation.h"
#include "analysis/wall_model.h"
#include "control/control_law.h"
#include "gate/curves.h"
#include "gate/number_format.h"
#include "kinematics/kinematics.h"

namespace hapticd::gate {
namespace {

using analysis::StiffnessLimit;
using analysis::TransferFunction;

double to_hz(double theta, double t) { return theta / (2.0 * std::numbers::pi * t); }

std::string passivity_reason(const config::Config& cfg, const GateReport& r) {
  const PassivityReport& p = r.passivity;
  const double b = cfg.device.damping[0];
  const double m = cfg.safety.passivity_margin;
  std::string s = "passivity: required damping b_req = " + format_number(p.required_damping) +
                  " N s/m exceeds (1 - safety.passivity_margin) x device.damping = (1 - " +
                  format_number(m) + ") x " + format_number(b) + " = " +
                  format_number(p.available_damping) + " N s/m";
  if (!p.note.empty()) return s + " (" + p.note + ")";
  s += " (worst at " + format_number(p.worst_frequency_hz) + " Hz, delay " +
       std::to_string(r.delay_samples) + " samples)";
  switch (p.max_stiffness.kind) {
    case StiffnessLimit::Kind::kBounded:
      s += "; wall.stiffness must be <= " + format_number(p.max_stiffness.value) +
           " N/m to pass (now " + format_number(cfg.wall.stiffness) + ")";
      break;
    case StiffnessLimit::Kind::kNone:
      s += "; no wall.stiffness passes, not even 0: wall.damping = " +
           format_number(cfg.wall.damping) +
           " N s/m alone needs more than the device has; lower it or add wall.coupling";
      break;
    case StiffnessLimit::Kind::kUnbounded:
      break;
  }
  if (std::isfinite(p.required_damping) && m < 1.0) {
    s += ", or device.damping >= " + format_number(p.required_damping / (1.0 - m)) + " N s/m";
  }
  return s;
}

void analyse_oscillation(const config::Config& cfg, const TransferFunction& e,
                         const std::optional<TransferFunction>& c, GateReport& r) {
  const double t = r.sample_period_s;
  if (c && r.coupling.admissible && analysis::poly_has_root_at(c->den, 1.0)) {
    r.oscillation.note = kCouplingPoleNote;
    return;
  }
  const analysis::OscillationCheck o =
      analysis::oscillation_check(oscillation_loop(cfg, e, c, r.delay_samples));
  r.oscillation = {o.applicable,          o.note,           o.tsai_colgate,         o.tsypkin,
                   o.tsai_colgate_margin, o.tsypkin_margin, to_hz(o.worst_theta, t)};
}

// Passivity (Roberts, Moore & Colgate) of what will run: H delayed by the wall's and the
// driver's samples, and the largest stiffness that passes.
void analyse_passivity(const config::Config& cfg, const TransferFunction& h,
                       const std::optional<TransferFunction>& c, GateReport& r) {
  const double t = r.sample_period_s, b = r.device_damping;
  const double eta = cfg.safety.operator_passivity_shortage;
  const analysis::PassivityBound pb = analysis::passivity_bound(h, t, r.delay_samples, eta);
  PassivityReport& p = r.passivity;
  p.required_damping = pb.required_damping;
  p.available_damping = (1.0 - cfg.safety.passivity_margin) * b;
  p.margin = (b - pb.required_damping) / b;
  p.worst_frequency_hz = pb.worst_frequency_hz;
  // A pass needs a finite bound: -inf or NaN from an overflow must never read as "passive".
  p.passive = std::isfinite(pb.required_damping) && std::isfinite(p.available_damping) &&
              pb.required_damping <= p.available_damping;
  p.note = pb.note;
  if (!std::isfinite(pb.required_damping) && p.note.empty()) {
    p.note = "the bound is not a finite number (" + format_number(pb.required_damping) +
             "): the analysis overflowed, so passivity is not proven";
  }
  p.max_stiffness = analysis::max_stiffness(
      [&](double k) {
        return analysis::contact_map(analysis::environment_filter(control::wall_params(cfg, k)), c);
      },
      t, r.delay_samples, eta, p.available_damping);
}

// The coupling (Naghshtabrizi & Hespanha): admissible, DSPR, and its transparency.
void analyse_coupling(const config::Config& cfg, const TransferFunction& h,
                      const TransferFunction& e, const TransferFunction& c, GateReport& r) {
  const double t = r.sample_period_s;
  const analysis::CouplingCheck cc = analysis::coupling_check(c, t, r.device_damping);
  r.coupling.admissible = cc.admissible;
  r.coupling.dspr = cc.dspr;
  r.coupling.dspr_min_real = cc.dspr_min_real;
  r.coupling.note = cc.note;
  const TransferFunction w{cfg.analysis.transparency_weight_numerator,
                           cfg.analysis.transparency_weight_denominator};
  const analysis::Extremum g = analysis::transparency_gamma(h, e, w);
  r.coupling.transparency_gamma = g.value;
  r.coupling.transparency_frequency_hz = to_hz(g.theta, t);
}

// What passes but deserves saying: the coupling's theorem where it does not hold or apply,
// a limit cycle not excluded, and what lies outside the theorems (Tustin's pole at -1,
// saturation, no_pull).
void add_warnings(const config::Config& cfg, bool coupled, GateReport& r) {
  if (coupled && r.coupling.admissible && !r.coupling.dspr) {
    r.warnings.push_back("coupling: Naghshtabrizi and Hespanha's Theorem 1 does not hold (" +
                         r.coupling.note + ")");
  }
  if (coupled && r.delay_samples > 0) {
    r.warnings.push_back(
        "coupling: Naghshtabrizi and Hespanha's Theorem 1 assumes no delay; "
        "with " +
        std::to_string(r.delay_samples) +
        " samples the passivity bound is what guarantees the loop");
  }
  if (!r.oscillation.applicable && !r.oscillation.note.empty() && !coupled) {
    r.warnings.push_back("oscillation: " + r.oscillation.note);
  } else if (r.oscillation.applicable && !r.oscillation.tsai_colgate) {
    r.warnings.push_back(
        "oscillation: the Tsai-Colgate criterion fails for the modelled operator (worst at " +
        format_number(r.oscillation.worst_frequency_hz) +
        " Hz): a limit cycle is not excluded for that hand");
  }
  if (cfg.wall.discretization == config::Discretization::kTustin) {
    r.warnings.push_back(
        "wall.discretization tustin: E(z) has a pole at z = -1, so after each release the "
        "damping term leaves a force alternating at the Nyquist frequency that never decays");
  }
  if (cfg.wall.stiffness > 0.0) {
    r.warnings.push_back("device.max_force = " + format_number(cfg.device.max_force[0]) +
                         " N saturates the wall beyond " +
                         format_number(cfg.device.max_force[0] / cfg.wall.stiffness * 1e3) +
                         " mm of penetration at rest: saturation is outside the theorems");
  }
  if (cfg.wall.no_pull) {
    r.warnings.push_back(
        "wall.no_pull clamps f >= 0: outside the theorems, which cover the linear wall only "
        "(the clamped pull can be the part that was dissipating energy on release)");
  }
}

}  // namespace

GateReport evaluate_gate(const config::Config& cfg, int device_delay_samples) {
  GateReport r;
  r.sample_period_s = cfg.loop.sample_period_s();
  r.device_delay_samples = device_delay_samples;
  r.delay_samples = device_delay_samples;
  r.device_damping = cfg.device.damping[0];
  // Several task axes: each wall along its normal over the workspace (workspace_gate.h), each
  // with its own delay added to the driver's.
  if (kinematics::joint_count(cfg.device.kinematics) != 1) {
    r.workspace = evaluate_workspace(cfg, device_delay_samples);
    r.reasons = r.workspace->reasons;
    r.pass = r.workspace->pass;
    return r;
  }
  r.wall_delay_samples = cfg.wall.delay_samples;
  r.delay_samples = cfg.wall.delay_samples + device_delay_samples;

  const TransferFunction e =
      analysis::environment_filter(control::wall_params(cfg, cfg.wall.stiffness));
  const std::optional<TransferFunction> c = control::coupling_filter(cfg);
  const TransferFunction h = analysis::contact_map(e, c);
  r.static_stiffness = analysis::static_stiffness(e, c);
  analyse_passivity(cfg, h, c, r);
  r.coupling.present = c.has_value();
  if (c) analyse_coupling(cfg, h, e, *c, r);
  analyse_oscillation(cfg, e, c, r);

  // Verdict: passivity decides; the other checks inform.
  if (!r.passivity.passive) r.reasons.push_back(passivity_reason(cfg, r));
  if (c && !r.coupling.admissible) r.reasons.push_back("coupling: " + r.coupling.note);
  r.pass = r.reasons.empty();
  add_warnings(cfg, c.has_value(), r);
  return r;
}

}  // namespace hapticd::gate
