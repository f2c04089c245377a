#include "control/scene.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hapticd::control {

Scene::Scene(std::span<const WallGeometry> geometry, std::span<const ControlLaw> laws,
             double max_move)
    : max_move_(max_move) {
  if (!(max_move > 0.0)) throw std::invalid_argument("a scene's walls must be able to move");
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
    place_[i] = g.point;
    walls_.emplace_back(laws[i]);
  }
}

void Scene::reset() noexcept {
  for (Controller& c : walls_) c.reset();
}

void Scene::continue_from(const Scene& from, std::span<const int> continues) noexcept {
  last_x_ = from.last_x_;
  for (std::size_t i = 0; i < walls_.size() && i < continues.size(); ++i) {
    const int j = continues[i];
    if (j < 0 || static_cast<std::size_t>(j) >= from.walls_.size()) continue;
    const WallGeometry& was = from.geometry_[static_cast<std::size_t>(j)];
    // A new normal turns the half-space at once (flipped, a device outside is suddenly deep
    // inside): that wall starts afresh, armed only once the device is outside it.
    if (was.normal != geometry_[i].normal) continue;
    walls_[i].continue_from(from.walls_[static_cast<std::size_t>(j)]);
    geometry_[i].point = was.point;
    sliding_ = sliding_ || geometry_[i].point != place_[i];
  }
}

void Scene::move_to(std::size_t i, const kinematics::Vec3& place) noexcept {
  if (i >= walls_.size() || !place.allFinite()) return;
  place_[i] = place;
  sliding_ = sliding_ || geometry_[i].point != place;
}

void Scene::slide() noexcept {
  if (!sliding_) return;  // the usual tick
  sliding_ = false;
  for (std::size_t i = 0; i < walls_.size(); ++i) {
    const kinematics::Vec3 way = place_[i] - geometry_[i].point;
    const double length = way.norm();
    // Within a step (or a way that is not finite: never here, the places are checked) it
    // arrives; otherwise one step of max_move_ along the way.
    geometry_[i].point = length <= max_move_ || !std::isfinite(length)
                             ? place_[i]
                             : geometry_[i].point + way * (max_move_ / length);
    sliding_ = sliding_ || geometry_[i].point != place_[i];
  }
}

void Scene::step_walls(const kinematics::Pose& pose, SceneStep& out) noexcept {
  out.count = walls_.size();
  out.pose_ok = pose.status == kinematics::Status::kOk && pose.x.allFinite();
  // A pose without a position (no assembly, no convergence) steps the walls where the
  // mechanism was last: the walls' histories must not jump, and no torque is written anyway.
  if (pose.x.allFinite()) last_x_ = pose.x;
  slide();
  out.force.setZero();
  for (std::size_t i = 0; i < walls_.size(); ++i) {
    out.walls[i] = walls_[i].step(coordinate(i, last_x_));
    out.flags |= out.walls[i].flags;
    // u is along s, the normal's direction: it pushes out of the wall where it is negative.
    out.force += out.walls[i].force_commanded * geometry_[i].normal;
  }
}

void Scene::map(const kinematics::Pose& pose, std::span<const double> commands,
                const kinematics::Vec3& limit, SceneStep& out,
                const kinematics::Vec3& added) const noexcept {
  out.force = added;
  for (std::size_t i = 0; i < walls_.size() && i < commands.size(); ++i) {
    out.force += commands[i] * geometry_[i].normal;
  }
  out.tau.setZero();
  if (!out.pose_ok) {
    out.scale = 0.0;
    return;
  }
  const kinematics::Saturated sat =
      kinematics::saturate(kinematics::joint_torques(pose, out.force), limit, pose.n);
  out.tau = sat.tau;
  out.saturation = sat.status;
  out.scale = sat.scale;
  if (sat.status == kinematics::SaturationStatus::kNonFinite) out.flags |= kControlNonFinite;
  if (sat.status == kinematics::SaturationStatus::kSaturated) out.flags |= kControlSaturated;
}

SceneStep Scene::step(const kinematics::Pose& pose, const kinematics::Vec3& limit) noexcept {
  SceneStep out;
  step_walls(pose, out);
  std::array<double, kMaxWalls> commands{};
  for (std::size_t i = 0; i < out.count; ++i) commands[i] = out.walls[i].force_commanded;
  map(pose, std::span<const double>(commands.data(), out.count), limit, out);
  return out;
}

ControlLaw task_wall_law(const config::Config& cfg, const config::TaskWallConfig& w) {
  config::Config one = cfg;
  one.wall = w.law;
  one.wall.position = 0.0;  // the law runs on s = n . (x - p): its wall is at s = 0,
  one.wall.normal = 1;      // occupying s > 0
  ControlLaw law = make_control_law(one);
  // device.max_force limits each joint, not a wall: the joints' saturation, which keeps the
  // force's direction, is the only limit, so a wall never saturates alone and its runaway
  // guard is the scene's (loop/scene_tick.h), which reads runaway_penetration: an explicit
  // safety.max_penetration, or none (the margin on the joints' saturation instead).
  law.max_force = std::numeric_limits<double>::infinity();
  if (!(cfg.safety.max_penetration > 0.0)) {
    law.runaway_penetration = std::numeric_limits<double>::infinity();
  }
  return law;
}

Scene make_scene(const config::Config& cfg) {
  std::vector<WallGeometry> geometry;
  std::vector<ControlLaw> laws;
  for (const config::TaskWallConfig& w : cfg.walls) {
    laws.push_back(task_wall_law(cfg, w));
    geometry.push_back({w.point, w.normal});
  }
  return Scene(geometry, laws, cfg.safety.max_wall_speed * cfg.loop.sample_period_s());
}

}  // namespace hapticd::control
