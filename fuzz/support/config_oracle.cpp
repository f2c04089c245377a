#include "support/config_oracle.h"

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <unordered_set>

#include "control/control_law.h"
#include "control/scene.h"
#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "support/check.h"
#include "wiring/registry.h"

namespace hapticd::fuzz {
namespace {

std::string show(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void require_finite(double v, std::string_view what) { require(std::isfinite(v), what, show(v)); }

// The coefficients the RT thread will multiply by every tick.
void require_finite_taps(const control::FilterCoefficients& f, std::string_view what) {
  for (std::size_t i = 0; i < f.num_taps; ++i) require_finite(f.num[i], what);
  for (std::size_t i = 0; i < f.den_taps; ++i) require_finite(f.den[i], what);
}

// The law one wall runs must be real numbers throughout: a pass that `run` could not start, or
// would start on a NaN, escapes here.
void check_law(const control::ControlLaw& law) {
  require(law.sample_period > 0.0 && std::isfinite(law.inv_sample_period),
          "pass with a control law whose 1/T is not finite", show(law.inv_sample_period));
  require_finite_taps(law.environment, "pass with a non-finite E(z) coefficient");
  if (law.has_coupling)
    require_finite_taps(law.coupling, "pass with a non-finite C(z) coefficient");
  require_finite(law.e0, "pass with a non-finite feed-through e0");
  require_finite(law.c0, "pass with a non-finite feed-through c0");
  require(std::isfinite(law.inv_one_plus_e0c0) && law.inv_one_plus_e0c0 > 0.0,
          "pass with 1/(1 + e0 c0) not finite and > 0", show(law.inv_one_plus_e0c0));
  require(law.max_force > 0.0 && std::isfinite(law.max_force),
          "pass with a saturation that is not finite and > 0", show(law.max_force));
}

// A pass over a workspace: every wall the device can reach compared finite numbers, walls that
// meet were covered together, and the scene `run` would build from them is real numbers.
void check_workspace_pass(const config::Config& cfg, const gate::WorkspaceReport& w) {
  require(w.pass, "a gate pass on a workspace that failed");
  require(w.walls.size() == cfg.walls.size(), "a workspace report without a verdict per wall");
  for (const gate::WallVerdict& v : w.walls) {
    if (!v.reached) continue;
    require(v.passive, "pass with a wall that is not passive");
    require_finite(v.required_damping, "pass on a wall's non-finite b_req");
    require(v.required_damping <= v.available_damping, "pass with a wall's b_req above b_n",
            show(v.required_damping) + " > " + show(v.available_damping));
    require(v.worst_damping <= v.grid_worst_damping, "the refinement went above the grid's worst");
  }
  require(!(w.corner_margin < 0.0) && !std::isnan(w.corner_margin),
          "pass with walls that meet uncovered", show(w.corner_margin));
  const control::Scene scene = control::make_scene(cfg);  // throws: a pass run cannot start
  require(scene.size() == cfg.walls.size(), "a scene without every wall");
}

// A pass enables the motor: everything the verdict compared, and everything the controller
// will compute with, must be a real number.
void check_pass(const config::Config& cfg, const gate::GateReport& r) {
  const double t = r.sample_period_s;
  require(std::isfinite(t) && t > 0.0, "pass with a sample period that is not finite and > 0",
          show(t));
  require(r.device_damping > 0.0 && std::isfinite(r.device_damping),
          "pass with a device damping that is not finite and > 0", show(r.device_damping));
  require(r.delay_samples >= 0 && r.delay_samples == r.wall_delay_samples + r.device_delay_samples,
          "pass with an inconsistent delay", std::to_string(r.delay_samples));

  if (r.workspace) {
    check_workspace_pass(cfg, *r.workspace);
    return;
  }
  const gate::PassivityReport& p = r.passivity;
  require(p.passive, "pass while the passivity check failed");
  require_finite(p.required_damping, "pass on a non-finite required damping b_req");
  require_finite(p.available_damping, "pass on a non-finite available damping");
  require(p.required_damping <= p.available_damping, "pass with b_req above the available damping",
          show(p.required_damping) + " > " + show(p.available_damping));
  require_finite(p.margin, "pass with a non-finite margin");
  const double nyquist_hz = 0.5 / t;
  require(p.worst_frequency_hz >= 0.0 && p.worst_frequency_hz <= nyquist_hz * (1.0 + 1e-9),
          "pass with a worst frequency outside [0, Nyquist]", show(p.worst_frequency_hz));
  require(!std::isnan(r.static_stiffness), "pass with a NaN static stiffness");
  if (r.coupling.present) {
    require(r.coupling.admissible, "pass with an inadmissible coupling");
    require(!std::isnan(r.coupling.dspr_min_real), "pass with a NaN DSPR margin");
  }

  // make_control_law throwing here would be a pass that `run` cannot start: it escapes.
  check_law(control::make_control_law(cfg));
}

// evaluate_gate is a pure function of the Config, and the loader determines a Config by its
// source name and effective document. Most mutants load to a configuration already seen (a
// broken line skipped, a comment changed) and the gate costs tens of milliseconds, so one
// already checked in this process is not checked again: ten times the executions per second.
// An input replayed alone is always evaluated. Bounded, so a long run cannot grow it forever.
bool first_time(const config::Config& cfg) {
  static std::unordered_set<std::string> seen;
  if (seen.size() >= 4096) seen.clear();
  return seen.insert(cfg.source_name + '\n' + cfg.effective_yaml).second;
}

}  // namespace

void check_config_error(const config::ConfigError& e,
                        std::initializer_list<std::string_view> prefixes) {
  require(!e.messages().empty(), "ConfigError without messages");
  for (const std::string& m : e.messages()) {
    bool named = false;
    for (std::string_view prefix : prefixes) {
      named = named || (m.size() > prefix.size() && m.starts_with(prefix));
    }
    require(named, "ConfigError message that names no source", m);
  }
}

void check_gate(const config::Config& cfg) {
  if (!first_time(cfg)) return;
  // The delay the driver declares from its own settings, as `check`, `verify` and `run` take it.
  const int device_delay = wiring::find_driver(cfg.device.driver).declared_delay(cfg);
  const gate::GateReport r = gate::evaluate_gate(cfg, device_delay);
  // `check` renders every verdict, passing or not.
  require(!gate::gate_to_json(r).dump().empty(), "empty JSON gate report");
  require(!gate::gate_to_text(r, cfg).empty(), "empty text gate report");

  require(r.pass == r.reasons.empty(), "a verdict must fail exactly when it gives reasons");
  for (const std::string& reason : r.reasons) require(!reason.empty(), "empty gate reason");
  if (r.pass) check_pass(cfg, r);
}

}  // namespace hapticd::fuzz
