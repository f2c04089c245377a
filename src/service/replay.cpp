#include "service/replay.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>

#include "control/controller.h"
#include "service/config_source.h"

namespace hapticd::service {
namespace {

using telemetry::TickRecord;

// One configuration's controller walking the log, with its series.
struct Walker {
  std::unique_ptr<control::Controller> law;
  ForceSeries series;
  double last_command = 0.0;  // u_{k-1}
  double work_x = 0.0;        // where the last step was taken
  bool have_work_x = false;

  void restart(const config::Config& cfg) {
    law = std::make_unique<control::Controller>(control::make_control_law(cfg));
    last_command = 0.0;
    have_work_x = false;
  }
  void swap_to(const config::Config& cfg) {
    auto next = std::make_unique<control::Controller>(control::make_control_law(cfg));
    next->continue_from(*law);
    law = std::move(next);
  }
  // One ordinary record; the output when the controller is stepped.
  std::optional<control::ControlOutput> step(bool stepped, double x) {
    std::optional<control::ControlOutput> out;
    if (stepped) {
      if (have_work_x) series.wall_energy_j += last_command * (x - work_x);
      work_x = x;
      have_work_x = true;
      out = law->step(x);
      add(out->force_commanded, out->penetration, out->flags & control::kControlContact,
          out->flags & control::kControlSaturated);
    }
    last_command = out ? out->force_commanded : 0.0;
    series.commanded.push_back(last_command);
    return out;
  }
  void add(double u, double p, bool contact, bool saturated) {
    series.max_abs_force = std::max(series.max_abs_force, std::abs(u));
    series.max_penetration = std::max(series.max_penetration, p);
    series.contact_ticks += contact ? 1 : 0;
    series.saturated_ticks += saturated ? 1 : 0;
  }
};

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// The logged series, counted the way the loop counts (from the records alone).
void log_tick(ForceSeries& s, const TickRecord& r, bool stepped, double& last_u, double& last_x,
              bool& have_x) {
  if (stepped) {
    if (have_x) s.wall_energy_j += last_u * (r.position - last_x);
    last_x = r.position;
    have_x = true;
  }
  last_u = r.force_commanded;
  s.commanded.push_back(r.force_commanded);
  s.max_abs_force = std::max(s.max_abs_force, std::abs(r.force_commanded));
  s.max_penetration = std::max(s.max_penetration, r.penetration);
  s.contact_ticks += (r.flags & telemetry::kFlagContact) ? 1 : 0;
  s.saturated_ticks += (r.flags & telemetry::kFlagSaturated) ? 1 : 0;
}

struct State {
  const telemetry::LogContents& log;
  const std::string& name;
  const config::Config* other_cfg;
  config::Config own_cfg;
  Walker own, other;
  std::size_t next_change = 0;  // into log.reloads
  double last_u = 0.0, last_x = 0.0;
  bool have_x = false;
};

// A marker record: a reload swaps the own law (continuing it), a re-arming starts both afresh.
// False when the replay cannot go on (a reload whose configuration is not in the log).
bool take_marker(State& st, const TickRecord& r, ReplayResult& out) {
  if (r.marker != telemetry::kMarkerReloadAccepted && r.marker != telemetry::kMarkerRearmed) {
    return true;  // a refused reload changes nothing
  }
  const auto& changes = st.log.reloads;
  const bool has_config =
      st.next_change < changes.size() && changes[st.next_change].first_tick == r.tick;
  if (has_config) {
    st.own_cfg =
        config_from_log(changes[st.next_change].config_text,
                        st.name + " (configuration from tick " + std::to_string(r.tick) + ")");
    ++st.next_change;
  }
  if (r.marker == telemetry::kMarkerReloadAccepted) {
    if (!has_config) {
      out.stopped = "tick " + std::to_string(r.tick) +
                    ": a reload whose configuration is not in the log (its block is missing)";
      return false;
    }
    st.own.swap_to(st.own_cfg);
    ++out.reloads;
    return true;
  }
  st.own.restart(st.own_cfg);
  if (st.other_cfg != nullptr) st.other.restart(*st.other_cfg);
  st.last_u = 0.0;
  st.have_x = false;
  ++out.rearms;
  return true;
}

void compare(const TickRecord& r, const control::ControlOutput& o, ReplayResult& out) {
  ++out.compared;
  if (same_bits(o.force_computed, r.force_computed) &&
      same_bits(o.force_commanded, r.force_commanded)) {
    return;
  }
  if (out.differing++ == 0) out.first_difference = r.tick;
}

}  // namespace

config::Config config_from_log(const std::string& text, const std::string& name) {
  return load_config_text_checked(text, name, ".");
}

ReplayResult replay_log(const telemetry::LogContents& log, const std::string& log_name,
                        const config::Config* other) {
  ReplayResult out;
  State st{log,   log_name,
           other, config_from_log(log.header.config_text, log_name + " (its configuration)"),
           {},    {},
           0,     0.0,
           0.0,   false};
  st.own.restart(st.own_cfg);
  if (other != nullptr) st.other.restart(*other);
  std::optional<std::uint64_t> last_tick;
  for (const TickRecord& r : log.records) {
    if (r.marker != telemetry::kMarkerNone) {
      if (!take_marker(st, r, out)) break;
      continue;
    }
    if (last_tick && r.tick != *last_tick + 1) {
      out.stopped = "ticks " + std::to_string(*last_tick + 1) + " to " +
                    std::to_string(r.tick - 1) + " are missing from the log";
      break;
    }
    last_tick = r.tick;
    // The loop steps the controller unless it had no position (none yet, or a fault before
    // the step); a faulted tick ends its run, so whether it stepped does not reach later ticks.
    const bool stepped = (r.flags & (telemetry::kFlagNoPosition | telemetry::kFlagFault)) == 0;
    out.ticks.push_back(r.tick);
    out.positions.push_back(r.position);
    log_tick(out.logged, r, stepped, st.last_u, st.last_x, st.have_x);
    if (const auto o = st.own.step(stepped, r.position)) compare(r, *o, out);
    if (other != nullptr) st.other.step(stepped, r.position);
  }
  out.own = std::move(st.own.series);
  if (other != nullptr) out.other = std::move(st.other.series);
  return out;
}

}  // namespace hapticd::service
