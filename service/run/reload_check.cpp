#include "service/run/reload_check.h"

#include <yaml-cpp/yaml.h>

#include "wiring/registry.h"

namespace hapticd::service {
namespace {

// A section of the effective document as text ("" when absent), to compare sections whose
// meaning the service does not know (a driver's own section, the simulated plant). The
// documents are the files as written (and --set): a section left out where the running one
// spelled out its defaults counts as a change, which errs on the side of a restart.
std::string section(const std::string& yaml, const std::string& a, const std::string& b) {
  const YAML::Node root = YAML::Load(yaml);
  if (!root.IsMap()) return "";
  const YAML::Node outer = root[a];
  if (!outer.IsDefined() || !outer.IsMap()) return "";
  const YAML::Node node = outer[b];
  if (!node.IsDefined() || node.IsNull()) return "";
  YAML::Emitter out;
  out << node;
  return out.c_str();
}

}  // namespace

std::vector<std::string> reload_blockers(const config::Config& running,
                                         const config::Config& next) {
  std::vector<std::string> out;
  const auto differs = [&](bool changed, const std::string& key, const std::string& why) {
    if (changed) out.push_back(key + ": " + why + "; that needs a restart");
  };
  // The mechanism the loop's scene maps through, and the joints' limits it saturates at (a
  // device of one joint's limit is its law's, which a reload swaps).
  differs(section(running.effective_yaml, "device", "kinematics") !=
              section(next.effective_yaml, "device", "kinematics"),
          "device.kinematics", "a different mechanism");
  differs(kinematics::joint_count(running.device.kinematics) > 1 &&
              running.device.max_force != next.device.max_force,
          "device.max_force", "new joint limits for a device of several joints");
  const config::LoopConfig &a = running.loop, &b = next.loop;
  differs(a.rate_hz != b.rate_hz, "loop.rate_hz", "a new sample rate");
  differs(a.clock != b.clock, "loop.clock", "a new clock");
  differs(a.rt_priority != b.rt_priority || a.cpu != b.cpu, "loop.rt_priority/cpu",
          "new real-time settings for the loop thread");
  differs(a.overrun_fault_streak != b.overrun_fault_streak, "loop.overrun_fault_streak",
          "a new fault check in the loop");
  const std::string& drv = running.device.driver;
  differs(drv != next.device.driver, "device.driver", "a different device");
  // A driver without a section of its own (the sim: its plant is device.sim, compared below).
  const bool has_section = wiring::find_driver(drv).read_section != nullptr;
  differs(drv == next.device.driver && has_section &&
              section(running.effective_yaml, "device", drv) !=
                  section(next.effective_yaml, "device", drv),
          "device." + drv, "a differently configured device");
  differs(!(running.device.sim == next.device.sim), "device.sim", "a different simulated plant");
  const config::SafetyConfig &s = running.safety, &t = next.safety;
  differs(s.max_speed != t.max_speed || s.stale_fault_ticks != t.stale_fault_ticks ||
              s.sequence_gap_fault != t.sequence_gap_fault,
          "safety.max_speed/stale_fault_ticks/sequence_gap_fault", "new fault checks in the loop");
  // The check is made when output is enabled, from the plan the loop was built with.
  differs(!(s.direction_check == t.direction_check), "safety.direction_check",
          "a new direction check (it runs as output is enabled)");
  // The passivity observer credits b and bounds its damping by m; it spans the whole run.
  differs(running.device.mass != next.device.mass ||
              running.device.damping != next.device.damping ||
              s.passivity_controller != t.passivity_controller ||
              s.passivity_max_damping != t.passivity_max_damping,
          "device.mass/damping, safety.passivity_controller/passivity_max_damping",
          "new passivity observer settings");
  differs(s.client_force_hold_ms != t.client_force_hold_ms ||
              s.client_force_ramp_ms != t.client_force_ramp_ms ||
              s.client_force_energy_j != t.client_force_energy_j,
          "safety.client_force_hold_ms/ramp_ms/energy_j",
          "a new observer of the clients' force (it spans the run)");
  differs(running.telemetry.log_path != next.telemetry.log_path ||
              running.telemetry.ring_capacity != next.telemetry.ring_capacity,
          "telemetry", "a different tick log");
  return out;
}

}  // namespace hapticd::service
