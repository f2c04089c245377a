#include "control/scene.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace hapticd::control {

Scene::Scene(std::span<const WallGeometry> geometry, std::span<const ControlLaw> laws) {
  if (geometry.size() != laws.size()) {
    throw std::invalid_argument("a scene needs one law per wall");
  }
  if (geometry.size() > kMaxWalls) {
    throw std::invalid_argument("a scene holds at most " + std::to_string(kMaxWalls) +
                                " walls, got " + std::to_string(geometry.size()));
  }
  walls_.reserve(geometry.size());
  for (std::size_t i = 0; i < geometry.size(); ++i) {
    const WallGeometry& g = geometry[i];
    if (!g.point.allFinite() || !g.normal.allFinite() || std::abs(g.normal.norm() - 1.0) > 1e-9) {
      throw std::invalid_argument("wall " + std::to_string(i) +
                                  ": its point must be finite and its normal a unit vector");
    }
    geometry_[i] = g;
    walls_.emplace_back(laws[i]);
  }
}

void Scene::reset() noexcept {
  for (Controller& c : walls_) c.reset();
}

SceneStep Scene::step(const kinematics::Pose& pose, const kinematics::Vec3& limit) noexcept {
  SceneStep out;
  out.count = walls_.size();
  out.pose_ok = pose.status == kinematics::Status::kOk && pose.x.allFinite();
  // A pose without a position (no assembly, no convergence) steps the walls where the
  // mechanism was last: the walls' histories must not jump, and no torque is written anyway.
  if (pose.x.allFinite()) last_x_ = pose.x;
  const kinematics::Vec3& x = last_x_;
  for (std::size_t i = 0; i < walls_.size(); ++i) {
    const WallGeometry& g = geometry_[i];
    const double s = g.normal.dot(x - g.point);
    out.walls[i] = walls_[i].step(s);
    out.flags |= out.walls[i].flags;
    // u is along s, the normal's direction: it pushes out of the wall where it is negative.
    out.force += out.walls[i].force_commanded * g.normal;
  }
  if (!out.pose_ok) {
    out.scale = 0.0;
    return out;
  }
  const kinematics::Saturated sat =
      kinematics::saturate(kinematics::joint_torques(pose, out.force), limit, pose.n);
  out.tau = sat.tau;
  out.saturation = sat.status;
  out.scale = sat.scale;
  if (sat.status == kinematics::SaturationStatus::kNonFinite) out.flags |= kControlNonFinite;
  if (sat.status == kinematics::SaturationStatus::kSaturated) out.flags |= kControlSaturated;
  return out;
}

Scene make_scene(const config::Config& cfg) {
  std::vector<WallGeometry> geometry;
  std::vector<ControlLaw> laws;
  for (const config::TaskWallConfig& w : cfg.walls) {
    config::Config one = cfg;
    one.wall = w.law;
    one.wall.position = 0.0;  // the law runs on s = n . (x - p): its wall is at s = 0,
    one.wall.normal = 1;      // occupying s > 0
    laws.push_back(make_control_law(one));
    geometry.push_back({w.point, w.normal});
  }
  return Scene(geometry, laws);
}

}  // namespace hapticd::control
