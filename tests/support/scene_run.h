// The loop as `hapticd run` runs a device of several joints, in freerun: cfg's scene with the
// loop's observer on each of its channels, for `ticks` ticks, on a device the caller has
// configured and enabled. Each tick's record into `ring` when given; the loop's own
// allocations into `allocations` when given. One definition for every driver's tests of
// several joints.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "alloc_counter.h"
#include "config/config.h"
#include "control/controller.h"
#include "control/scene.h"
#include "drivers/device.h"
#include "loop/servo_loop.h"

namespace hapticd::testing {

inline loop::LoopResult run_scene_loop(const config::Config& cfg, Device& device,
                                       std::uint64_t ticks,
                                       telemetry::SpscRing<telemetry::TickRecord>* ring = nullptr,
                                       std::uint64_t* allocations = nullptr) {
  control::Controller controller(control::make_control_law(cfg));  // unused at several joints
  auto scene = std::make_unique<control::Scene>(control::make_scene(cfg));
  const std::size_t channels = scene->channels();
  loop::SceneWalls walls(std::move(scene), std::vector<control::ObserverParams>(
                                               channels, control::observer_params(cfg, 0)));
  loop::SceneState state(cfg.device.kinematics, walls, cfg.device.max_force.per_joint());
  loop::LoopOptions o;
  o.sample.realtime = false;
  o.sample.period_ns = std::llround(cfg.loop.sample_period_s() * 1e9);
  o.sample.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  o.sample.sequence_modulus = device.info().sequence_modulus;
  o.max_ticks = ticks;
  o.scene = &state;
  loop::ServoLoop servo(device, controller, ring, o);
  const std::atomic<bool> stop{false};
  const AllocationScope scope;
  const loop::LoopResult r = servo.run(stop);
  if (allocations != nullptr) *allocations = scope.count();
  return r;
}

}  // namespace hapticd::testing
