// The loop tests' simulated delta (config/sim-delta.yaml, edited) and what runs it: its
// device, its walls (an observer per channel) and the scene's state.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "control/scene.h"
#include "freerun.h"
#include "loop/servo_loop.h"
#include "sim/sim_device.h"

namespace hapticd::loop {

inline std::string delta_yaml() {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/sim-delta.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// config/sim-delta.yaml with its text `from` replaced by `to`.
inline config::Config delta_config(const std::string& from = "", const std::string& to = "") {
  std::string yaml = delta_yaml();
  if (!from.empty()) {
    const auto at = yaml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) yaml.replace(at, from.size(), to);
  }
  return config::load_config_text(yaml, "sim-delta.yaml");
}

// cfg's scene with the loop's observer parameters on each channel.
inline SceneWalls scene_walls(const config::Config& cfg) {
  auto scene = std::make_unique<control::Scene>(control::make_scene(cfg));
  const std::size_t channels = scene->channels();
  return SceneWalls(std::move(scene), std::vector<control::ObserverParams>(
                                          channels, control::observer_params(cfg, 0)));
}

struct SceneRig {
  explicit SceneRig(const config::Config& c)
      : cfg(c),
        device(cfg.device, cfg.loop.sample_period_s()),
        controller(control::make_control_law(cfg)),
        walls(scene_walls(cfg)),
        state(cfg.device.kinematics, walls, cfg.device.max_force.per_joint()) {
    device.configure();
    device.enable();
  }
  LoopOptions options(std::uint64_t ticks) {
    LoopOptions o = freerun(ticks);
    o.scene = &state;
    return o;
  }
  config::Config cfg;
  sim::SimDevice device;
  control::Controller controller;  // unused at several joints, as the loop's signature asks
  SceneWalls walls;
  SceneState state;
};

}  // namespace hapticd::loop
