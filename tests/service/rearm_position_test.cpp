// Where `hapticctl clear-fault` may re-arm from: outside the wall of a device of one joint, and
// outside every wall of the scene of a device of several (its joints' forward solution; an
// attractor never counts), refused with the wall and the depth otherwise.
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "config/config_loader.h"
#include "kinematics/kinematics.h"
#include "service/run/rearm_position.h"

namespace hapticd::service {
namespace {

config::Config example(const std::string& name) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/" + name);
  std::stringstream text;
  text << in.rdbuf();
  return config::load_config_text(text.str(), name);
}

std::array<PositionSample, 3> joints_at(const config::Config& cfg, const kinematics::Vec3& x) {
  const kinematics::JointSolution q = kinematics::inverse(cfg.device.kinematics, x);
  std::array<PositionSample, 3> s{};
  for (int j = 0; j < 3; ++j) s[static_cast<std::size_t>(j)].position = q.q[j];
  return s;
}

TEST(RearmPosition, OneJointOutsideItsWallOnly) {
  const config::Config cfg = example("sim.yaml");  // a wall at 0, normal +1
  std::array<PositionSample, 1> s{};
  s[0].position = -0.01;
  EXPECT_EQ(rearm_refusal(cfg, s), "");
  s[0].position = 0.005;
  EXPECT_EQ(rearm_refusal(cfg, s), "the device is 5 mm inside the wall: move it out first");
}

TEST(RearmPosition, SeveralJointsOutsideEveryWallOfTheScene) {
  const config::Config cfg = example("sim-delta.yaml");  // a box of six walls about (0, 0, 0.11)
  EXPECT_EQ(rearm_refusal(cfg, joints_at(cfg, {0.0, 0.0, 0.11})), "") << "the box's middle";
  EXPECT_EQ(rearm_refusal(cfg, joints_at(cfg, {0.023, 0.0, 0.11})),
            "the device is 3 mm inside walls[0]: move it out first");
  EXPECT_EQ(rearm_refusal(cfg, joints_at(cfg, {0.0, -0.025, 0.11})),
            "the device is 5 mm inside walls[3]: move it out first");
  std::array<PositionSample, 3> nan{};
  nan[1].position = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(rearm_refusal(cfg, nan), "the device's position is not a number");
}

}  // namespace
}  // namespace hapticd::service
