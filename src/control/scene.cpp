#include "control/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "kinematics/kinematics.h"

namespace hapticd::control {

Scene::Scene(std::span<const WallGeometry> geometry, std::span<const ControlLaw> laws,
             double max_move)
    : walls_(geometry.size()), max_move_(max_move) {
  if (!(max_move > 0.0)) throw std::invalid_argument("a scene's walls must be able to move");
  if (geometry.size() != laws.size()) {
    throw std::invalid_argument("a scene needs one law per wall");
  }
  if (geometry.size() > kMaxWalls) {
    throw std::invalid_argument("a scene holds at most " + std::to_string(kMaxWalls) +
                                " walls, got " + std::to_string(geometry.size()));
  }
  channels_.reserve(kMaxChannels);
  for (std::size_t i = 0; i < geometry.size(); ++i) {
    const WallGeometry& g = geometry[i];
    const std::string wall = "wall " + std::to_string(i);
    if (!g.point.allFinite()) throw std::invalid_argument(wall + ": its point must be finite");
    if (g.attractor() && (g.attractor_axes > 3 || !(g.max_force > 0.0))) {
      throw std::invalid_argument(wall +
                                  ": an attractor pulls along 1 to 3 task axes with a "
                                  "positive max_force");
    }
    if (!g.attractor() && (!g.normal.allFinite() || std::abs(g.normal.norm() - 1.0) > 1e-9)) {
      throw std::invalid_argument(wall + ": its normal must be a unit vector");
    }
    geometry_[i] = g;
    place_[i] = g.point;
    fresh_[i] = g.attractor();
    attractors_ = attractors_ || g.attractor();
    first_[i] = channels_.size();
    for (int k = 0; k < std::max(g.attractor_axes, 1); ++k) {
      wall_of_[channels_.size()] = i;
      direction_[channels_.size()] = g.attractor() ? kinematics::Vec3::Unit(k) : g.normal;
      channels_.emplace_back(laws[i]);
    }
  }
  first_[geometry.size()] = channels_.size();
  any_fresh_ = attractors_;
}

void Scene::reset() noexcept {
  for (Controller& c : channels_) c.reset();
  for (std::size_t i = 0; i < walls_; ++i) fresh_[i] = geometry_[i].attractor();
  any_fresh_ = attractors_;
}

void Scene::continue_from(const Scene& from, std::span<const int> continues) noexcept {
  last_x_ = from.last_x_;
  for (std::size_t i = 0; i < walls_ && i < continues.size(); ++i) {
    const int j = continues[i];
    if (j < 0 || static_cast<std::size_t>(j) >= from.walls_) continue;
    const WallGeometry& was = from.geometry_[static_cast<std::size_t>(j)];
    // A new normal turns the half-space at once (flipped, a device outside is suddenly deep
    // inside): that wall starts afresh, armed only once the device is outside it. So does a
    // wall that became an attractor, or the other way round.
    if (was.normal != geometry_[i].normal || was.attractor_axes != geometry_[i].attractor_axes) {
      continue;
    }
    const std::size_t theirs = from.first_[static_cast<std::size_t>(j)];
    for (std::size_t c = first_[i]; c < first_[i + 1]; ++c) {
      channels_[c].continue_from(from.channels_[theirs + (c - first_[i])]);
    }
    geometry_[i].point = was.point;
    fresh_[i] = from.fresh_[static_cast<std::size_t>(j)];
    any_fresh_ = any_fresh_ || fresh_[i];
    sliding_ = sliding_ || geometry_[i].point != place_[i];
  }
}

void Scene::move_to(std::size_t i, const kinematics::Vec3& place) noexcept {
  if (i >= walls_ || !place.allFinite()) return;
  place_[i] = place;
  sliding_ = sliding_ || geometry_[i].point != place;
}

void Scene::slide() noexcept {
  if (!sliding_) return;  // the usual tick
  sliding_ = false;
  for (std::size_t i = 0; i < walls_; ++i) {
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

void Scene::limit_attractor(std::size_t i, SceneStep& out) const noexcept {
  kinematics::Vec3 f = kinematics::Vec3::Zero();
  for (std::size_t c = first_[i]; c < first_[i + 1]; ++c) {
    f += out.channels[c].force_commanded * direction_[c];
  }
  const double norm = f.norm();
  if (!(norm > geometry_[i].max_force)) return;  // within, or not finite (the loop faults)
  const double scale = geometry_[i].max_force / norm;
  for (std::size_t c = first_[i]; c < first_[i + 1]; ++c) {
    out.channels[c].force_commanded *= scale;
    out.channels[c].flags |= kControlSaturated;
  }
}

void Scene::step_walls(const kinematics::Pose& pose, SceneStep& out) noexcept {
  out.count = channels_.size();
  out.pose_ok = pose.status == kinematics::Status::kOk && pose.x.allFinite();
  // A pose without a position (no assembly, no convergence) steps the walls where the
  // mechanism was last: the walls' histories must not jump, and no torque is written anyway.
  if (pose.x.allFinite()) {
    last_x_ = pose.x;
    if (any_fresh_) start_attractors(pose.x);
  }
  slide();
  out.force.setZero();
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    out.channels[c] = channels_[c].step(coordinate(c, last_x_));
  }
  if (attractors_) {
    for (std::size_t i = 0; i < walls_; ++i) {
      if (geometry_[i].attractor()) limit_attractor(i, out);
    }
  }
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    const ControlOutput& o = out.channels[c];
    out.flags |= o.flags;
    if (o.flags & kControlContact) out.contact |= 1u << wall_of_[c];
    // u is along s, the channel's direction: it pushes out of a wall where it is negative.
    out.force += o.force_commanded * direction_[c];
  }
}

void Scene::start_attractors(const kinematics::Vec3& x) noexcept {
  any_fresh_ = false;
  for (std::size_t i = 0; i < walls_; ++i) {
    if (!fresh_[i]) continue;
    fresh_[i] = false;  // from where the device is: no force, no filter history to kick
    geometry_[i].point = x;
    sliding_ = true;
  }
}

void Scene::map(const kinematics::Pose& pose, std::span<const double> commands,
                const kinematics::Vec3& limit, SceneStep& out,
                const kinematics::Vec3& added) const noexcept {
  out.force = added;
  for (std::size_t c = 0; c < channels_.size() && c < commands.size(); ++c) {
    out.force += commands[c] * direction_[c];
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
  std::array<double, kMaxChannels> commands{};
  for (std::size_t c = 0; c < out.count; ++c) commands[c] = out.channels[c].force_commanded;
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
  if (!(cfg.safety.max_penetration > 0.0) || w.kind == config::WallKind::kAttractor) {
    law.runaway_penetration = std::numeric_limits<double>::infinity();
  }
  if (w.kind == config::WallKind::kAttractor) {
    law.linear_contact = true;  // bilateral: it pulls back from either side of its point
    law.require_outside_start = false;
  }
  return law;
}

Scene make_scene(const config::Config& cfg) {
  std::vector<WallGeometry> geometry;
  std::vector<ControlLaw> laws;
  for (const config::TaskWallConfig& w : cfg.walls) {
    laws.push_back(task_wall_law(cfg, w));
    const bool attractor = w.kind == config::WallKind::kAttractor;
    geometry.push_back({w.point, w.normal,
                        attractor ? kinematics::joint_count(cfg.device.kinematics) : 0,
                        w.max_force});
  }
  return Scene(geometry, laws, cfg.safety.max_wall_speed * cfg.loop.sample_period_s());
}

}  // namespace hapticd::control
