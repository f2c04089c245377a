// A scene of two joints against the HID driver's simulated device, as `hapticd run --loopback`
// runs it, in freerun (config/hid-report-xy.yaml, config/hid-pid-xy.yaml): the loop's result,
// every tick's record, where the simulated joints ended, and what the device felt after.
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

#include "alloc_counter.h"
#include "control/controller.h"
#include "control/scene.h"
#include "drivers/hid/hid_device.h"
#include "loop/scene_tick.h"
#include "loop/servo_loop.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::hid::testing {

struct XyRun {
  loop::LoopResult result;
  std::vector<telemetry::TickRecord> records;
  kinematics::Vec3 joints = kinematics::Vec3::Zero();  // the simulated stage's at the end
  bool peer_on_after = true;
  double peer_force_after = 1.0;
  // Right after a faulted run, before the disable: what the driver's fault path left.
  bool peer_on_at_fault = true;
  std::array<double, 2> commands_at_fault{1.0, 1.0};
  std::uint64_t contact_before_fault = 0;
  // The first run's (the whole run's without a fault): the loop's allocations, and what the
  // HID driver sent.
  std::uint64_t allocations = 1, output_reports = 0;
};

// `ticks` ticks of the scene of `cfg` against its driver's simulated device, in freerun.
inline XyRun run_xy(const config::Config& cfg, std::uint64_t ticks, bool fault_at_half = false) {
  wiring::Loopback pair = wiring::find_driver(cfg.device.driver).make_loopback(cfg);
  const auto* hid = dynamic_cast<const HidDevice*>(pair.device.get());
  XyRun out;
  sim::PeerRunner runner(*pair.peer);
  sim::PacedDevice device(std::move(pair.device), runner);
  control::Controller controller(control::make_control_law(cfg));  // unused at two joints
  loop::SceneWalls walls(
      std::make_unique<control::Scene>(control::make_scene(cfg)),
      std::vector<control::ObserverParams>(cfg.walls.size(), control::observer_params(cfg, 0)));
  loop::SceneState state(cfg.device.kinematics, walls, cfg.device.max_force.per_joint());
  telemetry::SpscRing<telemetry::TickRecord> ring(8192);
  loop::LoopOptions o;
  o.sample.realtime = false;
  o.sample.period_ns = std::llround(cfg.loop.sample_period_s() * 1e9);
  o.sample.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  o.sample.sequence_gap_fault = cfg.safety.sequence_gap_fault;
  o.sample.sequence_modulus = 0;
  o.scene = &state;
  device.configure();
  o.sample.sequence_modulus = device.info().sequence_modulus;
  device.enable();
  const std::atomic<bool> stop{false};
  o.max_ticks = fault_at_half ? ticks / 2 : ticks;
  loop::ServoLoop servo(device, controller, &ring, o);
  {
    const hapticd::testing::AllocationScope scope;
    out.result = servo.run(stop);
    out.allocations = scope.count();
  }
  if (hid != nullptr) out.output_reports = hid->hid_counts().output_reports;
  if (fault_at_half) {
    out.contact_before_fault = out.result.count(loop::kCounterContactTicks);
    pair.peer->inject(sim::PeerFault::kDeviceFault);
    loop::ServoLoop rest(device, controller, &ring, o);
    out.result = rest.run(stop);
    runner.wait_idle();
    out.peer_on_at_fault = pair.peer->output_on();
    out.commands_at_fault = {device.last_command(0), device.last_command(1)};
  }
  out.records.resize(ring.size_approx());
  out.records.resize(ring.pop_many(out.records.data(), out.records.size()));
  device.disable();
  runner.wait_idle();
  out.peer_on_after = pair.peer->output_on();
  out.peer_force_after = pair.peer->applied_force();
  if (const sim::JointPlant* p = pair.peer->joint_plant()) out.joints = p->joint_positions();
  device.close();
  return out;
}

// The mean penetration of ticks [from, to): where the press rests.
inline double mean_penetration(const XyRun& r, std::size_t from, std::size_t to) {
  double sum = 0.0;
  for (std::size_t k = from; k < to; ++k) sum += r.records[k].penetration;
  return sum / static_cast<double>(to - from);
}

// Where the hand's spring and the first wall balance along its normal, the hand's set-point
// `depth` along its direction from its origin: K p = k_h (n . (set-point - point) - p).
inline double balanced_penetration(const config::Config& cfg, double depth) {
  const config::TaskWallConfig& wall = cfg.walls.front();
  const config::OperatorSpec& hand = cfg.device.sim.op;
  const double reach = wall.normal.dot(hand.origin + depth * hand.direction - wall.point);
  return hand.stiffness * reach / (wall.law.stiffness + hand.stiffness);
}

}  // namespace hapticd::drivers::hid::testing
