#include "service/commands/curves_command.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "gate/curves.h"
#include "gate/gate.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "verify/passivity_sweep.h"
#include "wiring/registry.h"

namespace hapticd::service {
namespace {

using nlohmann::json;

const char* kind_name(analysis::StiffnessLimit::Kind k) {
  switch (k) {
    case analysis::StiffnessLimit::Kind::kBounded:
      return "bounded";
    case analysis::StiffnessLimit::Kind::kUnbounded:
      return "unbounded";
    case analysis::StiffnessLimit::Kind::kNone:
      return "none";
  }
  return "none";
}

// The stiffness at which the measured b_req (verify's simulation) reaches the damping the gate
// allows, by bisection on K up to 1.5 times the analytic one; none when it cannot be measured.
std::optional<double> measured_stiffness(config::Config cfg, int delay, double analytic) {
  const double available = (1.0 - cfg.safety.passivity_margin) * cfg.device.damping[0];
  const auto passes = [&](double k) {
    cfg.wall.stiffness = k;
    return verify::verify_passivity(cfg, delay).measured_required_damping <= available;
  };
  double lo = 0.0, hi = 1.5 * analytic;
  try {
    if (passes(hi)) return std::nullopt;  // not bracketed: nothing to place
    for (int i = 0; i < 20; ++i) {
      const double mid = 0.5 * (lo + hi);
      (passes(mid) ? lo : hi) = mid;
    }
  } catch (const std::exception&) {
    return std::nullopt;  // a wall the measurement cannot cover (e.g. it leaves contact)
  }
  return 0.5 * (lo + hi);
}

json zwidth_json(const config::Config& cfg, int delay, bool measure) {
  const std::vector<gate::ZwidthPoint> curve = gate::zwidth_curve(cfg, delay);
  json points = json::array(), measured = json::array();
  for (const gate::ZwidthPoint& p : curve) {
    const bool bounded = p.max_stiffness.kind == analysis::StiffnessLimit::Kind::kBounded;
    points.push_back({{"damping", p.damping},
                      {"max_stiffness", bounded ? json(p.max_stiffness.value) : json(nullptr)},
                      {"kind", kind_name(p.max_stiffness.kind)}});
  }
  // A handful of points along the bounded part of the curve, measured.
  for (std::size_t i = 0; measure && i < curve.size();
       i += std::max<std::size_t>(1, curve.size() / 6)) {
    const gate::ZwidthPoint& p = curve[i];
    if (p.max_stiffness.kind != analysis::StiffnessLimit::Kind::kBounded ||
        !(p.max_stiffness.value > 0.0)) {
      continue;
    }
    config::Config at = cfg;
    at.wall.damping = p.damping;
    if (const auto k = measured_stiffness(at, delay, p.max_stiffness.value)) {
      measured.push_back({{"damping", p.damping},
                          {"stiffness", *k},
                          {"analytic_stiffness", p.max_stiffness.value}});
    }
  }
  return {{"points", points},
          {"measured", measured},
          {"measured_how",
           "for a wall damping B on the curve, the stiffness at which the required damping "
           "measured on the simulated loop (hapticd verify: imposed motion up to Nyquist, the "
           "damping below which the device hands the operator net energy) reaches the damping "
           "the gate allows, by bisection"}};
}

json nyquist_json(const config::Config& cfg, int delay, const gate::GateReport& report) {
  std::string note;
  const std::vector<gate::NyquistPoint> curve = gate::nyquist_curve(cfg, delay, note);
  json theta = json::array(), re = json::array(), im = json::array();
  for (const gate::NyquistPoint& p : curve) {
    theta.push_back(p.theta);
    re.push_back(p.l.real());
    im.push_back(p.l.imag());
  }
  const gate::OscillationReport& o = report.oscillation;
  return {{"theta", theta},
          {"re", re},
          {"im", im},
          {"note", note.empty() ? o.note : note},
          {"applicable", o.applicable},
          {"tsai_colgate", o.tsai_colgate},
          {"tsypkin", o.tsypkin},
          {"tsai_colgate_margin", o.tsai_colgate_margin},
          {"tsypkin_margin", o.tsypkin_margin},
          {"worst_theta", o.worst_frequency_hz * 2.0 * M_PI * cfg.loop.sample_period_s()}};
}

}  // namespace

int curves_command(const ConfigOptions& options, bool measure) {
  const config::Config cfg = load_config(options);
  require_one_joint(cfg, "curves");
  const int delay = wiring::find_driver(cfg.device.driver).declared_delay(cfg);
  const gate::GateReport report = gate::evaluate_gate(cfg, delay);
  const json j{
      {"config", cfg.source_name},
      {"sample_period_s", report.sample_period_s},
      {"delay_samples", report.delay_samples},
      {"device_mass", cfg.device.mass[0]},
      {"device_damping", cfg.device.damping[0]},
      {"available_damping", report.passivity.available_damping},
      {"discretization",
       cfg.wall.discretization == config::Discretization::kTustin ? "tustin" : "backward"},
      {"coupling", cfg.wall.coupling.present},
      {"configured",
       {{"damping", cfg.wall.damping}, {"stiffness", cfg.wall.stiffness}, {"pass", report.pass}}},
      {"zwidth", zwidth_json(cfg, delay, measure)},
      {"nyquist", nyquist_json(cfg, delay, report)}};
  return write_stdout(j.dump(1) + "\n") ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
