#include "gate/gate_report_format.h"

#include <cmath>
#include <sstream>

#include "gate/number_format.h"

namespace hapticd::gate {
namespace {

using nlohmann::json;

}  // namespace

std::string stiffness_note(const analysis::StiffnessLimit& lim) {
  switch (lim.kind) {
    case analysis::StiffnessLimit::Kind::kBounded:
      return "";
    case analysis::StiffnessLimit::Kind::kUnbounded:
      return "unbounded: every stiffness up to " + format_number(lim.value) + " N/m passes";
    case analysis::StiffnessLimit::Kind::kNone:
      return "none: no stiffness passes, not even 0";
  }
  return "";
}

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json gate_to_json(const GateReport& r) {
  const PassivityReport& p = r.passivity;
  json j;
  j["sample_period_s"] = r.sample_period_s;
  j["delay_samples"] = r.delay_samples;
  j["wall_delay_samples"] = r.wall_delay_samples;
  j["device_delay_samples"] = r.device_delay_samples;
  j["device_damping"] = r.device_damping;
  j["passivity"] = {
      {"required_damping", finite_or_null(p.required_damping)},
      {"available_damping", p.available_damping},
      {"margin", finite_or_null(p.margin)},
      {"worst_frequency_hz",
       std::isfinite(p.required_damping) ? json(p.worst_frequency_hz) : json(nullptr)},
      {"passive", p.passive},
      {"max_stiffness", p.max_stiffness.kind == analysis::StiffnessLimit::Kind::kBounded
                            ? json(p.max_stiffness.value)
                            : json(nullptr)},
      {"max_stiffness_note", stiffness_note(p.max_stiffness)},
      {"note", p.note}};
  const OscillationReport& o = r.oscillation;
  j["oscillation"] = {
      {"applicable", o.applicable},
      {"tsai_colgate", o.applicable ? json(o.tsai_colgate) : json(nullptr)},
      {"tsypkin", o.applicable ? json(o.tsypkin) : json(nullptr)},
      {"tsai_colgate_margin", o.applicable ? json(o.tsai_colgate_margin) : json(nullptr)},
      {"tsypkin_margin", o.applicable ? json(o.tsypkin_margin) : json(nullptr)},
      {"worst_frequency_hz", o.applicable ? json(o.worst_frequency_hz) : json(nullptr)},
      {"note", o.note}};
  const CouplingReport& c = r.coupling;
  j["coupling"] = {
      {"present", c.present},
      {"dspr", c.present ? json(c.dspr) : json(nullptr)},
      {"dspr_min_real", c.present && c.admissible ? json(c.dspr_min_real) : json(nullptr)},
      {"transparency_gamma", c.present ? finite_or_null(c.transparency_gamma) : json(nullptr)},
      {"static_stiffness", r.static_stiffness},
      {"note", c.note}};
  j["workspace"] = r.workspace ? workspace_to_json(*r.workspace) : json(nullptr);
  j["verdict"] = r.pass ? "pass" : "fail";
  j["reasons"] = r.reasons;
  j["warnings"] = r.warnings;
  return j;
}

namespace {

// "  key<padding>value": the table's row.
void row(std::ostream& os, const std::string& k, const std::string& v) {
  os << "  " << k << std::string(k.size() < 26 ? 26 - k.size() : 1, ' ') << v << "\n";
}

void passivity_rows(const GateReport& r, const config::Config& cfg, std::ostream& os) {
  const PassivityReport& p = r.passivity;
  os << "passivity (Roberts, Moore & Colgate)\n";
  row(os, "required damping b_req",
      format_number(p.required_damping) + " N s/m" +
          (std::isfinite(p.required_damping) ? " at " + format_number(p.worst_frequency_hz) + " Hz"
                                             : " (" + p.note + ")"));
  row(os, "allowed (margin " + format_number(cfg.safety.passivity_margin * 100) + " %)",
      "b_req <= " + format_number(p.available_damping) + " N s/m");
  row(os, "achieved margin",
      std::isfinite(p.margin) ? format_number(p.margin * 100, 3) + " % of b" : "none");
  const std::string note =
      p.max_stiffness.kind == analysis::StiffnessLimit::Kind::kBounded
          ? format_number(p.max_stiffness.value) + " N/m"
      : p.max_stiffness.kind == analysis::StiffnessLimit::Kind::kUnbounded
          ? "unbounded (tried up to " + format_number(p.max_stiffness.value) + " N/m)"
          : "none, not even 0";
  row(os, "largest passing K", note + " (configured " + format_number(cfg.wall.stiffness) + ")");
  row(os, "static stiffness H(1)",
      format_number(r.static_stiffness) + " N/m (what a steady push feels)");
}

void oscillation_and_coupling_rows(const GateReport& r, const config::Config& cfg,
                                   std::ostream& os) {
  const OscillationReport& o = r.oscillation;
  os << "oscillation (Tsai & Colgate; operator k_h " +
            format_number(cfg.analysis.operator_stiffness) + " N/m, b_h " +
            format_number(cfg.analysis.operator_damping) + " N s/m)\n";
  if (o.applicable) {
    row(os, "Tsai-Colgate",
        std::string(o.tsai_colgate ? "holds" : "fails") + " (margin " +
            format_number(o.tsai_colgate_margin, 3) + ", worst at " +
            format_number(o.worst_frequency_hz) + " Hz)");
    row(os, "Tsypkin",
        std::string(o.tsypkin ? "holds" : "fails") + " (margin " +
            format_number(o.tsypkin_margin, 3) + ")");
  } else {
    row(os, "criteria", o.note);
  }
  const CouplingReport& c = r.coupling;
  if (!c.present) {
    os << "coupling                    none\n";
    return;
  }
  os << "coupling (Naghshtabrizi & Hespanha)\n";
  row(os, "DSPR (Theorem 1)",
      std::string(c.dspr ? "holds" : "fails") +
          (c.admissible ? " (min Re " + format_number(c.dspr_min_real) + ")" : "") +
          (c.note.empty() ? "" : "; " + c.note));
  row(os, "transparency gamma",
      format_number(c.transparency_gamma) + " at " + format_number(c.transparency_frequency_hz) +
          " Hz");
}

}  // namespace

std::string gate_to_text(const GateReport& r, const config::Config& cfg) {
  std::ostringstream os;
  os << "hapticd check: " << cfg.source_name << "\n";
  row(os, "sample period T",
      format_number(r.sample_period_s * 1e3) + " ms (" + format_number(1.0 / r.sample_period_s) +
          " Hz)");
  row(os, "delay",
      r.workspace ? "driver " + std::to_string(r.device_delay_samples) +
                        " samples + each wall's delay_samples"
                  : std::to_string(r.delay_samples) + " samples (wall " +
                        std::to_string(r.wall_delay_samples) + " + driver " +
                        std::to_string(r.device_delay_samples) + ")");
  std::string b = format_number(r.device_damping) + " N s/m";
  if (r.workspace) {
    b.clear();
    for (const double d : r.workspace->joint_damping)
      b += (b.empty() ? "" : ", ") + format_number(d);
    b += " (each joint's, in its own units)";
  }
  row(os, "device damping b", b);
  if (r.workspace) {
    workspace_rows(*r.workspace, cfg, os);
  } else {
    passivity_rows(r, cfg, os);
    oscillation_and_coupling_rows(r, cfg, os);
  }
  os << "verdict                     " << (r.pass ? "PASS" : "FAIL") << "\n";
  for (const std::string& s : r.reasons) os << "  fail: " << s << "\n";
  for (const std::string& s : r.warnings) os << "  note: " << s << "\n";
  return os.str();
}

}  // namespace hapticd::gate
