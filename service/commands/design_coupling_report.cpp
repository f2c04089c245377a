#include "service/commands/design_coupling_report.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>

#include "analysis/coupling.h"
#include "analysis/transparency_weight.h"
#include "analysis/wall_model.h"
#include "control/control_law.h"
#include "gate/number_format.h"

namespace hapticd::service {
namespace {

using analysis::TransferFunction;
using gate::format_number;
using nlohmann::json;

TransferFunction configured_weight(const config::Config& cfg) {
  return {cfg.analysis.transparency_weight_numerator, cfg.analysis.transparency_weight_denominator};
}

// |W(1) E(1)|^2 with the configured W: no coupling that passes Theorem 1 does better.
double configured_floor(const DesignReport& r) {
  const double w1 = analysis::dc_gain(configured_weight(r.cfg));
  const double e1 = analysis::dc_gain(r.spec.environment);
  return w1 * w1 * e1 * e1;
}

// Both measures of one coupling (or of the bare wall, nullopt).
struct Measures {
  double felt = 0.0;
  double configured = 0.0;
  double required_damping = 0.0;
  double static_stiffness = 0.0;
};

Measures measures(const DesignReport& r, const std::optional<TransferFunction>& c) {
  const TransferFunction& e = r.spec.environment;
  const TransferFunction h = analysis::contact_map(e, c);
  const TransferFunction wc = configured_weight(r.cfg);
  const TransferFunction wf =
      analysis::felt_weight(wc, r.options.felt_from_hz, r.spec.sample_period);
  return {analysis::transparency_gamma(h, e, wf).value,
          analysis::transparency_gamma(h, e, wc).value,
          analysis::passivity_bound(h, r.spec.sample_period, r.spec.delay_samples, 0.0)
              .required_damping,
          analysis::static_stiffness(e, c)};
}

std::string coefficients(const analysis::Polynomial& p) {
  std::ostringstream os;
  os.precision(17);
  os << "[";
  for (std::size_t i = 0; i < p.size(); ++i) os << (i ? ", " : "") << p[i];
  return os.str() + "]";
}

json measures_json(const Measures& m) {
  return {{"gamma_felt", m.felt},
          {"gamma_configured", m.configured},
          {"required_damping", m.required_damping},
          {"static_stiffness", m.static_stiffness}};
}

// |E|, |H| and |W_felt (H - E)|^2 on a logarithmic grid from 0.01 Hz to Nyquist.
json curve_json(const DesignReport& r, const std::optional<TransferFunction>& configured) {
  const double t = r.spec.sample_period, nyquist = 0.5 / t;
  const TransferFunction& e = r.spec.environment;
  const TransferFunction wf =
      analysis::felt_weight(configured_weight(r.cfg), r.options.felt_from_hz, t);
  const TransferFunction hd = analysis::contact_map(e, r.design.coupling);
  const std::optional<TransferFunction> hc =
      configured ? std::optional(analysis::contact_map(e, configured)) : std::nullopt;
  json f = json::array(), bare = json::array(), des = json::array(), conf = json::array();
  json err_des = json::array(), err_conf = json::array();
  constexpr int kPoints = 120;
  for (int i = 0; i < kPoints; ++i) {
    const double hz = 0.01 * std::pow(nyquist / 0.01, i / (kPoints - 1.0));
    const double th = 2.0 * std::numbers::pi * hz * t;
    const auto at = [&](const TransferFunction& x) { return analysis::frequency_response(x, th); };
    f.push_back(hz);
    bare.push_back(std::abs(at(e)));
    des.push_back(std::abs(at(hd)));
    err_des.push_back(std::norm(at(wf) * (at(hd) - at(e))));
    if (hc) {
      conf.push_back(std::abs(at(*hc)));
      err_conf.push_back(std::norm(at(wf) * (at(*hc) - at(e))));
    }
  }
  return {{"frequency_hz", f},
          {"bare_wall", bare},
          {"designed", des},
          {"configured_coupling", hc ? conf : json(nullptr)},
          {"felt_error_designed", err_des},
          {"felt_error_configured_coupling", hc ? err_conf : json(nullptr)}};
}

// |E| and |H| at a few frequencies a hand feels: the curve in the text.
std::string curve_text(const DesignReport& r, const std::optional<TransferFunction>& configured) {
  const double t = r.spec.sample_period;
  const TransferFunction& e = r.spec.environment;
  const TransferFunction hd = analysis::contact_map(e, r.design.coupling);
  std::ostringstream os;
  os << "  transparency          f (Hz): |E| bare wall, |H| designed"
     << (configured ? ", |H| configured coupling" : "") << " (N/m)\n";
  for (double hz : {0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0}) {
    if (hz >= 0.5 / t) break;
    const double th = 2.0 * std::numbers::pi * hz * t;
    os << "    " << format_number(hz) << ": "
       << format_number(std::abs(analysis::frequency_response(e, th))) << ", "
       << format_number(std::abs(analysis::frequency_response(hd, th)));
    if (configured) {
      os << ", "
         << format_number(
                std::abs(analysis::frequency_response(analysis::contact_map(e, configured), th)));
    }
    os << "\n";
  }
  return os.str();
}

const char* status_name(const DesignReport& r) {
  if (r.not_needed) return "not needed";
  switch (r.design.status) {
    case analysis::CouplingDesign::Status::kDesigned:
      return r.gate_passed ? "designed" : "refused by the gate";
    case analysis::CouplingDesign::Status::kNotConverged:
      return "not converged";
    case analysis::CouplingDesign::Status::kNoCoupling:
      return "no coupling found";
  }
  return "no coupling found";
}

}  // namespace

std::string DesignReport::failure() const {
  if (not_needed) {
    return "the wall passes the gate without a coupling (b_req " +
           format_number(bare_gate.passivity.required_damping) +
           " <= " + format_number(bare_gate.passivity.available_damping) +
           " N s/m): none is designed, since every coupling Theorem 1 admits would make it "
           "yield under a steady push (H(1) = 0)";
  }
  if (design.status != analysis::CouplingDesign::Status::kDesigned) {
    return std::string(status_name(*this)) + ": " + design.note;
  }
  std::string why;
  for (const std::string& reason : gate.reasons) why += (why.empty() ? "" : "; ") + reason;
  if (why.empty()) why = "Theorem 1's DSPR condition fails by the gate's check";
  return "the gate's exact check refused the design: " + why;
}

std::string design_report_json(const DesignReport& r) {
  const std::optional<TransferFunction> configured = control::coupling_filter(r.cfg);
  json j{
      {"config", r.cfg.source_name},
      {"status", status_name(r)},
      {"order", r.spec.order},
      {"weight", r.options.weight},
      {"felt_from_hz", r.options.felt_from_hz},
      {"solver", r.solver},
      {"delay_samples", r.spec.delay_samples},
      {"device_damping", r.spec.device_damping},
      {"allowed_damping", r.spec.allowed_damping},
      {"steps", r.design.steps},
      {"sdp_solves", r.design.sdp_solves},
      {"gamma_floor_configured", configured_floor(r)},
      {"bare_wall", measures_json(measures(r, std::nullopt))},
      {"configured_coupling", configured ? measures_json(measures(r, configured)) : json(nullptr)}};
  if (!r.designed()) {
    j[r.not_needed ? "note" : "failure"] = r.failure();
    return j.dump(1) + "\n";
  }
  const analysis::CouplingDesign& d = r.design;
  j["designed"] = measures_json(measures(r, d.coupling));
  j["gamma_designed_for"] = d.verdict.gamma;
  j["gamma_lower"] = d.gamma_lower;
  j["gamma_seed"] = d.gamma_seed;
  j["nu"] = {{"d", d.nu.d}, {"dc", d.nu.dc}};
  j["creep_m_per_s_per_n"] = d.nu.d / r.spec.sample_period;
  j["gate"] = {{"pass", r.gate.pass},
               {"required_damping", r.gate.passivity.required_damping},
               {"available_damping", r.gate.passivity.available_damping},
               {"dspr", r.gate.coupling.dspr},
               {"dspr_min_real", r.gate.coupling.dspr_min_real}};
  j["coupling"] = {{"numerator", d.coupling.num}, {"denominator", d.coupling.den}};
  j["curve"] = curve_json(r, configured);
  return j.dump(1) + "\n";
}

std::string design_report_text(const DesignReport& r) {
  const std::optional<TransferFunction> configured = control::coupling_filter(r.cfg);
  const analysis::CouplingDesign& d = r.design;
  std::ostringstream os;
  const auto line = [&](const std::string& what, const Measures& m) {
    os << "  " << what << "gamma felt " << format_number(m.felt) << ", configured "
       << format_number(m.configured) << "; b_req " << format_number(m.required_damping)
       << " N s/m; H(1) " << format_number(m.static_stiffness) << " N/m\n";
  };
  os << "hapticd design-coupling: " << r.cfg.source_name << "\n"
     << "  wall                  K = " << format_number(r.cfg.wall.stiffness)
     << " N/m, B = " << format_number(r.cfg.wall.damping)
     << " N s/m, T = " << format_number(r.spec.sample_period) << " s, delay "
     << r.spec.delay_samples << " samples, b = " << format_number(r.spec.device_damping)
     << " N s/m (b_req allowed <= " << format_number(r.spec.allowed_damping) << ")\n"
     << "  design                order " << r.spec.order << ", weight " << r.options.weight
     << (r.options.weight == "felt" ? " from " + format_number(r.options.felt_from_hz) + " Hz"
                                    : std::string())
     << ", " << d.steps << " steps, " << d.sdp_solves << " SDPs (" << r.solver << ")\n";
  line("bare wall:            ", measures(r, std::nullopt));
  if (configured) line("configured coupling:  ", measures(r, configured));
  if (!r.designed()) {
    os << "  result                " << r.failure() << "\n";
    return os.str();
  }
  line("designed coupling:    ", measures(r, d.coupling));
  os << "  gamma search          " << format_number(d.verdict.gamma) << " found ("
     << format_number(d.gamma_seed) << " by cone complementarity at order "
     << std::min(r.spec.order, analysis::kConeComplementarityOrder)
     << ", then the pole search); the configured weight's floor "
     << format_number(configured_floor(r)) << " (H(1) = 0 for every admissible C)\n"
     << "  creep                 " << format_number(d.nu.d / r.spec.sample_period)
     << " m/s per N under a steady push (d = " << format_number(d.nu.d)
     << ", D_c = " << format_number(d.nu.dc) << ")\n"
     << "  gate                  PASS: b_req " << format_number(r.gate.passivity.required_damping)
     << " <= " << format_number(r.gate.passivity.available_damping)
     << " N s/m; Theorem 1 DSPR, min Re " << format_number(r.gate.coupling.dspr_min_real) << "\n"
     << curve_text(r, configured)
     << "# paste into the configuration:\nwall:\n  coupling:\n    numerator: "
     << coefficients(d.coupling.num) << "\n    denominator: " << coefficients(d.coupling.den)
     << "\n";
  return os.str();
}

}  // namespace hapticd::service
