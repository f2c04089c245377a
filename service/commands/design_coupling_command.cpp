#include "service/commands/design_coupling_command.h"

#include <iostream>
#include <stdexcept>

#include "analysis/sdp_solver.h"
#include "analysis/transparency_weight.h"
#include "analysis/wall_model.h"
#include "config/config_loader.h"
#include "control/control_law.h"
#include "gate/number_format.h"
#include "service/commands/design_coupling_report.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "wiring/registry.h"

namespace hapticd::service {
namespace {

using analysis::TransferFunction;
using gate::format_number;

config::ConfigError usage(const config::Config& cfg, const std::string& what) {
  return config::ConfigError({cfg.source_name + ": design-coupling: " + what});
}

analysis::CouplingSpec spec_of(const config::Config& cfg, const DesignCouplingOptions& o,
                               int delay) {
  if (o.weight != "felt" && o.weight != "configured") {
    throw usage(cfg, "--weight must be felt or configured, got '" + o.weight + "'");
  }
  if (cfg.wall.discretization == config::Discretization::kTustin) {
    throw usage(cfg,
                "wall.discretization tustin: E(z) has a pole at z = -1, so W (H - E) is "
                "unbounded for every coupling; design for backward");
  }
  analysis::CouplingSpec s;
  s.environment = analysis::environment_filter(control::wall_params(cfg, cfg.wall.stiffness));
  const TransferFunction w{cfg.analysis.transparency_weight_numerator,
                           cfg.analysis.transparency_weight_denominator};
  s.sample_period = cfg.loop.sample_period_s();
  try {
    s.weight = o.weight == "felt" ? analysis::felt_weight(w, o.felt_from_hz, s.sample_period) : w;
  } catch (const std::invalid_argument& e) {
    throw usage(cfg,
                std::string("--felt-from-hz ") + format_number(o.felt_from_hz) + ": " + e.what());
  }
  s.device_damping = cfg.device.damping[0];
  s.allowed_damping = (1.0 - cfg.safety.passivity_margin) * cfg.device.damping[0] -
                      cfg.safety.operator_passivity_shortage;
  s.delay_samples = delay;
  s.order = o.order;
  return s;
}

void print_step(const analysis::DesignStep& s, int max_steps) {
  using O = analysis::CclResult::Outcome;
  if (s.phase == analysis::DesignStep::Phase::kPoles) {
    using K = analysis::PoleSearchStep::Kind;
    const analysis::PoleSearchStep& p = s.poles;
    std::cerr << "design-coupling: step " << s.index << ": order " << p.order << ", "
              << (p.kind == K::kReshape ? std::string("numerator reshaped at the poles so far")
                  : p.kind == K::kScan  ? std::string("poles placed from a grid")
                                        : "poles moved by up to " + format_number(p.step))
              << (p.improved ? ": better" : ": no better") << "; best " << format_number(p.best)
              << "\n";
    return;
  }
  const char* what = s.outcome == O::kFound          ? "reached"
                     : s.outcome == O::kInfeasible   ? "infeasible (certified)"
                     : s.outcome == O::kSolverFailed ? "solver gave up"
                                                     : "not reached";
  std::cerr << "design-coupling: step " << s.index << "/" << max_steps
            << ": d = " << format_number(s.nu.d) << ", D_c = " << format_number(s.nu.dc)
            << ", gamma target " << format_number(s.target) << " " << what << " in " << s.iterations
            << " SDPs" << (s.found > 0.0 ? ", found " + format_number(s.found) : std::string())
            << "; best " << format_number(s.best) << ", lower " << format_number(s.lower) << "\n";
}

}  // namespace

int design_coupling_command(const DesignCouplingOptions& o) {
  const config::Config cfg = load_config(o.config);
  require_one_joint(cfg, "design-coupling");
  const int device_delay = wiring::find_driver(cfg.device.driver).declared_delay(cfg);
  const analysis::CouplingSpec spec = spec_of(cfg, o, cfg.wall.delay_samples + device_delay);
  analysis::DesignOptions options;
  options.max_steps = o.max_steps;
  options.max_ccl_iterations = o.max_iterations;
  if (o.max_steps < 1 || o.max_steps > 1000 || o.max_iterations < 1 || o.max_iterations > 1000) {
    throw usage(cfg, "--max-steps and --max-iterations must be 1 to 1000");
  }
  const std::unique_ptr<analysis::SdpSolver> solver = analysis::make_sdp_solver();
  try {
    analysis::validate_coupling_spec(spec);
  } catch (const std::invalid_argument& e) {
    throw usage(cfg, e.what());
  }
  // A wall the gate passes bare needs no coupling: say so instead of designing one.
  config::Config bare = cfg;
  bare.wall.coupling = {};
  gate::GateReport bare_gate = gate::evaluate_gate(bare, device_delay);
  const bool not_needed = bare_gate.pass;
  analysis::CouplingDesign design;
  if (!not_needed) {
    try {
      design = analysis::design_coupling(
          spec, options, *solver,
          [&](const analysis::DesignStep& s) { print_step(s, options.max_steps); });
    } catch (const std::invalid_argument& e) {
      throw usage(cfg, e.what());
    }
  }
  DesignReport report{
      cfg,   o,          device_delay,        spec, std::move(design), solver->name(), {},
      false, not_needed, std::move(bare_gate)};
  if (report.design.status == analysis::CouplingDesign::Status::kDesigned) {
    // The gate's own exact check of the configuration with the coupling pasted in.
    config::Config with = cfg;
    with.wall.coupling = {true, report.design.coupling.num, report.design.coupling.den};
    report.gate = gate::evaluate_gate(with, device_delay);
    report.gate_passed =
        report.gate.pass && report.gate.coupling.admissible && report.gate.coupling.dspr;
  }
  const std::string text = o.json ? design_report_json(report) : design_report_text(report);
  if (!report.designed() && !report.not_needed) {
    std::cerr << "hapticd: design-coupling: " << report.failure() << "\n";
  }
  if (!write_stdout(text)) return kExitRuntimeFault;
  return report.designed() || report.not_needed ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
