#include "service/commands/replay.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>

#include "control/controller.h"
#include "control/direction_probe.h"
#include "control/passivity_observer.h"
#include "gate/gate.h"
#include "loop/scene_tick.h"
#include "loop/tick.h"
#include "service/config_source.h"
#include "service/run/run_support.h"
#include "wiring/registry.h"

namespace hapticd::service {
namespace {

using telemetry::TickRecord;

// The driver's declared delay, which places the force acting over each period; none for a
// driver this build does not have (replay then takes 0 and says so: only the observer's
// figures depend on it, and the controller's forces only in damp mode).
std::optional<int> declared_delay(const config::Config& cfg) {
  for (const wiring::DriverEntry& d : wiring::registered_drivers()) {
    if (d.name == cfg.device.driver) return d.declared_delay(cfg);
  }
  return std::nullopt;
}

int device_delay(const config::Config& cfg) { return declared_delay(cfg).value_or(0); }

// Sample periods between two records (more than one after the loop skipped periods).
std::uint32_t periods_between(std::int64_t from_ns, std::int64_t to_ns, double period_s) {
  const double n = std::round(static_cast<double>(to_ns - from_ns) * 1e-9 / period_s);
  return n >= 1.0 ? static_cast<std::uint32_t>(n) : 1u;
}

// One configuration's controller and passivity observer walking the log, with its series.
// Each tick goes through the loop's own tick (loop/tick.h), so what the run computed comes
// back by construction.
struct Walker {
  std::unique_ptr<control::Controller> law;
  std::unique_ptr<control::PassivityObserver> observer;  // built once: it spans re-armings
  std::unique_ptr<control::DirectionProbe> probe;        // each arming's direction check
  SceneParts scene;  // a device of several joints: its walls and their observers, built once
  ForceSeries series;

  void restart(const config::Config& cfg) {
    if (kinematics::joint_count(cfg.device.kinematics) > 1) {
      // The loop's own scene, its observers crediting what the gate found along each normal.
      if (!scene.state) {
        DeviceInfo info;
        info.transport_delay_samples = device_delay(cfg);
        scene = make_scene_parts(cfg, info, gate::evaluate_gate(cfg, device_delay(cfg)));
      }
      scene.state->restart();
      return;
    }
    law = std::make_unique<control::Controller>(control::make_control_law(cfg));
    probe = std::make_unique<control::DirectionProbe>(control::probe_plan(cfg, device_delay(cfg)));
    if (!observer) {
      observer = std::make_unique<control::PassivityObserver>(
          control::observer_params(cfg, device_delay(cfg)));
    }
    observer->restart();
  }
  // `continues` (null: wall i from wall i, as before format 5) says which running wall each
  // new one goes on from, as the loop took it.
  void swap_to(const config::Config& cfg, const std::vector<int>* continues = nullptr) {
    if (scene.state) {  // the walls of several joints, going on from the running ones
      DeviceInfo info;
      info.transport_delay_samples = device_delay(cfg);
      auto next = make_scene_walls(cfg, info, gate::evaluate_gate(cfg, device_delay(cfg)),
                                   scene.walls.get(), continues);
      next->continue_from(*scene.walls);
      scene.state->walls = next.get();
      scene.walls = std::move(next);
      return;
    }
    auto next = std::make_unique<control::Controller>(control::make_control_law(cfg));
    next->continue_from(*law);
    law = std::move(next);
  }
  // A client's move (kMarkerWallMoved), as the loop took it.
  void move(std::size_t wall, const kinematics::Vec3& place) {
    if (scene.walls) scene.walls->scene->move_to(wall, place);
  }
  // One ordinary record: the loop's tick on its position when the loop stepped it, then what
  // was written (zero on a tick that faulted). The record this law makes of it, for a tick
  // stepped without a fault (the ones whose forces the log must reproduce).
  // The same for a device of several joints: the loop's scene tick.
  std::optional<TickRecord> step_scene(const TickRecord& logged, bool stepped, bool faulted,
                                       std::uint32_t periods) {
    TickRecord rec;
    loop::JointCommand c;
    if (stepped) {
      c = loop::step_scene_tick(*scene.state, loop::JointInput::recorded(logged, periods), rec);
    }
    const bool zero = faulted || c.faulted();
    loop::end_scene_tick(*scene.state, zero ? nullptr : &c, rec);
    series.commanded.push_back(rec.force_commanded);
    series.wall_energy_j = scene.walls->totals().wall_work_j;
    series.min_observer_energy_j = std::min(series.min_observer_energy_j, rec.observer_energy_j);
    series.damped_ticks += (rec.flags & telemetry::kFlagPassivityDamped) ? 1 : 0;
    if (!stepped || faulted) return std::nullopt;
    add(rec.force_commanded, rec.penetration, (rec.flags & telemetry::kFlagContact) != 0,
        (rec.flags & telemetry::kFlagSaturated) != 0);
    return rec;
  }
  std::optional<TickRecord> step(const TickRecord& logged, bool stepped, bool faulted,
                                 std::uint32_t periods) {
    if (scene.state) return step_scene(logged, stepped, faulted, periods);
    TickRecord rec;
    loop::TickCommand c;
    const bool checking = (logged.flags & telemetry::kFlagProbe) != 0;
    if (stepped) {
      c = loop::step_tick(*law, *observer, loop::TickInput::recorded(logged, periods), rec);
    } else if (checking) {  // the direction check's pulse, from the positions it saw
      c.command = probe->step(logged.position, periods);
    }
    if (faulted || c.non_finite) c = {};
    loop::end_tick(*observer, c, rec);
    series.commanded.push_back(c.command);
    series.wall_energy_j = observer->wall_work_j();
    series.min_observer_energy_j = observer->min_energy_j();
    series.damped_ticks = observer->damped_ticks();
    if ((!stepped && !checking) || faulted) return std::nullopt;
    if (checking) return rec;  // compared, but no wall acted
    add(rec.force_commanded, rec.penetration, (rec.flags & telemetry::kFlagContact) != 0,
        (rec.flags & telemetry::kFlagSaturated) != 0);
    return rec;
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

// The logged series, counted the way the loop counts (from the records alone): the work with
// an observer fed the logged commands, the observer's figures as recorded.
void log_tick(ForceSeries& s, control::PassivityObserver& work, const TickRecord& r, bool stepped,
              std::uint32_t periods) {
  if (r.joints > 1) {
    // Each wall's work needs its own force, which a record of several joints does not hold.
    s.wall_energy_j = std::nan("");
  } else {
    if (stepped) work.observe(r.position, loop::TickInput::recorded(r, periods).fresh, periods);
    work.commanded(r.force_commanded, 0.0);
    s.wall_energy_j = work.wall_work_j();
  }
  s.min_observer_energy_j = std::min(s.min_observer_energy_j, r.observer_energy_j);
  s.damped_ticks += (r.flags & telemetry::kFlagPassivityDamped) ? 1 : 0;
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
  std::size_t next_change = 0;                              // into log.reloads
  std::unique_ptr<control::PassivityObserver> logged_work;  // of the logged commands
};

// A marker record: a reload swaps the own law (continuing it), a client's move moves the own
// wall, a re-arming starts both afresh. False when the replay cannot go on (a reload whose
// configuration is not in the log).
bool take_marker(State& st, const TickRecord& r, ReplayResult& out) {
  if (r.marker == telemetry::kMarkerWallMoved) {
    st.own.move(r.deepest_wall, {r.task_position[0], r.task_position[1], r.task_position[2]});
    return true;
  }
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
    std::vector<int> continues;  // format 5 says it (several joints); before: wall i from i
    for (std::size_t i = 0; i < st.own_cfg.walls.size(); ++i) {
      continues.push_back(telemetry::continued_from(r.sequence, i));
    }
    st.own.swap_to(st.own_cfg, st.log.version >= 5 ? &continues : nullptr);
    ++out.reloads;
    return true;
  }
  st.own.restart(st.own_cfg);
  if (st.other_cfg != nullptr) st.other.restart(*st.other_cfg);
  st.logged_work->restart();
  ++out.rearms;
  return true;
}

// Forces bit for bit; from format 3 on, the observer's energy and damping too; from format 4
// on, every joint's torque.
void compare(const TickRecord& r, const TickRecord& s, std::uint32_t version, ReplayResult& out) {
  ++out.compared;
  const bool observer_same = version < 3 || (same_bits(s.observer_energy_j, r.observer_energy_j) &&
                                             same_bits(s.passivity_damping, r.passivity_damping));
  const bool joints_same = version < 4 || (same_bits(s.joint_force[0], r.joint_force[0]) &&
                                           same_bits(s.joint_force[1], r.joint_force[1]));
  if (same_bits(s.force_computed, r.force_computed) &&
      same_bits(s.force_commanded, r.force_commanded) && observer_same && joints_same) {
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
           0,     {}};
  st.own.restart(st.own_cfg);
  if (other != nullptr) st.other.restart(*other);
  if (!declared_delay(st.own_cfg)) {
    out.note = "device.driver " + st.own_cfg.device.driver +
               " is not in this build: its declared delay is taken as 0, so the passivity "
               "observer's figures (and, with safety.passivity_controller: damp, the forces) "
               "may not reproduce";
  }
  control::ObserverParams work = control::observer_params(st.own_cfg, device_delay(st.own_cfg));
  work.mode = config::PassivityControl::kObserve;
  st.logged_work = std::make_unique<control::PassivityObserver>(work);
  const double period = st.own_cfg.loop.sample_period_s();
  std::optional<std::uint64_t> last_tick;
  std::int64_t last_scheduled = 0;
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
    const std::uint32_t periods =
        last_tick ? periods_between(last_scheduled, r.scheduled_ns, period) : 1u;
    last_tick = r.tick;
    last_scheduled = r.scheduled_ns;
    // The loop steps the controller (and observes) when it has a position; format 3 says so
    // per tick. Before it, a faulted tick counts as not stepped: it ends its run, and nothing
    // but the observer (which those logs do not carry) outlives a run.
    const bool faulted = (r.flags & telemetry::kFlagFault) != 0;
    const bool stepped =
        log.version >= 3 ? (r.flags & telemetry::kFlagStepped) != 0
                         : (r.flags & (telemetry::kFlagNoPosition | telemetry::kFlagFault)) == 0;
    out.ticks.push_back(r.tick);
    out.positions.push_back(r.position);
    log_tick(out.logged, *st.logged_work, r, stepped, periods);
    if (const auto o = st.own.step(r, stepped, faulted, periods)) compare(r, *o, log.version, out);
    if (other != nullptr) st.other.step(r, stepped, faulted, periods);
  }
  out.own = std::move(st.own.series);
  if (other != nullptr) out.other = std::move(st.other.series);
  return out;
}

}  // namespace hapticd::service
