#include "service/run/rearm_position.h"

#include <cmath>
#include <limits>

#include "gate/number_format.h"
#include "kinematics/kinematics.h"

namespace hapticd::service {
namespace {

std::string inside(double depth, const std::string& what) {
  return "the device is " + gate::format_number(depth * 1e3) + " mm inside " + what +
         ": move it out first";
}

}  // namespace

std::string rearm_refusal(const config::Config& cfg, std::span<const PositionSample> samples) {
  for (const PositionSample& s : samples) {
    if (!std::isfinite(s.position)) return "the device's position is not a number";
  }
  if (samples.size() == 1 && cfg.walls.empty()) {
    const double p = cfg.wall.normal * (samples[0].position - cfg.wall.position);
    return p > 0.0 ? inside(p, "the wall") : "";
  }
  kinematics::Vec3 q = kinematics::Vec3::Zero();
  for (std::size_t j = 0; j < samples.size() && j < 3; ++j) {
    q[static_cast<Eigen::Index>(j)] = samples[j].position;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const kinematics::Pose pose = kinematics::forward(cfg.device.kinematics, q, {nan, nan, nan});
  if (pose.status == kinematics::Status::kOutsideWorkspace ||
      pose.status == kinematics::Status::kNoConvergence) {
    return std::string("the device's pose is not one hapticd renders walls at (") +
           kinematics::status_name(pose.status) + "): move it into the workspace first";
  }
  for (std::size_t i = 0; i < cfg.walls.size(); ++i) {
    const config::TaskWallConfig& w = cfg.walls[i];
    if (w.kind != config::WallKind::kWall) continue;
    const double depth = w.normal.dot(pose.x - w.point);
    if (depth > 0.0) return inside(depth, "walls[" + std::to_string(i) + "]");
  }
  return "";
}

}  // namespace hapticd::service
