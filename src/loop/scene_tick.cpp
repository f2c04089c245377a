#include "loop/scene_tick.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapticd::loop {

using kinematics::Vec3;

SceneWalls::SceneWalls(std::unique_ptr<control::Scene> s,
                       const std::vector<control::ObserverParams>& params)
    : scene(std::move(s)) {
  if (scene == nullptr || params.size() != scene->channels()) {
    throw std::invalid_argument("a scene's loop needs one passivity observer per channel");
  }
  observers.reserve(params.size());
  for (const control::ObserverParams& p : params) observers.emplace_back(p);
  continues.fill(-1);
}

void SceneWalls::Totals::add(const control::PassivityObserver& o) noexcept {
  energy_j += o.energy_j();
  min_energy_j += o.min_energy_j();
  wall_work_j += o.wall_work_j();
  damping_work_j += o.damping_work_j();
  negative_ticks = std::max(negative_ticks, o.negative_ticks());
  max_damping = std::max(max_damping, o.max_alpha());
}

void SceneWalls::continue_from(SceneWalls& running) noexcept {
  scene->continue_from(*running.scene, continues);
  std::array<bool, control::kMaxChannels> continued{};
  const control::Scene& was = *running.scene;
  for (std::size_t i = 0; i < scene->size(); ++i) {
    const int j = continues[i];
    if (j < 0 || static_cast<std::size_t>(j) >= was.size()) continue;
    const std::size_t mine = scene->first_channel(i), n = scene->first_channel(i + 1) - mine;
    const std::size_t theirs = was.first_channel(static_cast<std::size_t>(j));
    // A wall that became an attractor (or one of other axes) starts its observers afresh.
    if (was.first_channel(static_cast<std::size_t>(j) + 1) - theirs != n) continue;
    for (std::size_t k = 0; k < n; ++k) {
      observers[mine + k].continue_from(running.observers[theirs + k]);
      continued[theirs + k] = true;
    }
  }
  ended = running.ended;
  for (std::size_t j = 0; j < running.observers.size(); ++j) {
    if (!continued[j]) ended.add(running.observers[j]);
  }
}

SceneWalls::Totals SceneWalls::totals() const noexcept {
  Totals t = ended;
  for (const control::PassivityObserver& o : observers) t.add(o);
  return t;
}

SceneState::SceneState(const kinematics::Kinematics& k, SceneWalls& w, const Vec3& lim)
    : kinematics(k), walls(&w), limit(lim), guess(Vec3::Constant(std::nan(""))) {}

void SceneState::restart() noexcept {
  for (control::PassivityObserver& o : walls->observers) o.restart();
  walls->scene->reset();
  guess = Vec3::Constant(std::nan(""));
  deepest.fill(0.0);
  stepped = 0;
}

namespace {

// The runaway guard on the deepest wall (scene_tick.h). RT-safe.
bool running_away(SceneState& st, const control::SceneStep& step, double s,
                  std::size_t wall) noexcept {
  for (std::size_t i = st.deepest.size() - 1; i > 0; --i) st.deepest[i] = st.deepest[i - 1];
  st.deepest[0] = s;
  ++st.stepped;
  const bool saturated = step.saturation == kinematics::SaturationStatus::kSaturated;
  const double explicit_bound =
      st.walls->scene->size() > 0 ? st.walls->scene->wall_law(wall).runaway_penetration : 0.0;
  const bool deeper = std::isfinite(explicit_bound)
                          ? s > explicit_bound
                          : step.scale * config::kRunawayMargin < 1.0 && s > 0.0;
  if (!saturated || !deeper || st.stepped < st.deepest.size()) return false;
  constexpr std::size_t w = control::Controller::kRunawayWindow;
  const double last = st.deepest[0] - st.deepest[w - 1];
  const double before = st.deepest[w - 1] - st.deepest[2 * w - 1];
  return last >= before;  // not braked: pulled in, pushed through, or held there
}

// The record's fields of the walls' step: the deepest wall's (an attractor is not one: it is
// meant to pull from afar, its axes' coordinates no depth), the contact bits, the flags.
void record_walls(const control::Scene& scene, const control::SceneStep& step,
                  telemetry::TickRecord& rec) noexcept {
  std::size_t deepest = step.count;
  for (std::size_t c = 0; c < step.count; ++c) {
    if (scene.geometry(scene.wall_of(c)).attractor()) continue;
    if (deepest == step.count || step.channels[c].penetration > step.channels[deepest].penetration)
      deepest = c;
  }
  rec.wall_contact |= step.contact;
  if (deepest < step.count) {
    const control::ControlOutput& w = step.channels[deepest];
    rec.deepest_wall = static_cast<std::uint8_t>(scene.wall_of(deepest));
    rec.penetration = w.penetration;
    rec.velocity = w.velocity;
    rec.force_computed = w.force_computed;
  }
  rec.flags |= step.flags;
}

}  // namespace

JointCommand step_scene_tick(SceneState& st, const JointInput& in,
                             telemetry::TickRecord& rec) noexcept {
  const kinematics::Pose pose = kinematics::forward(st.kinematics, in.q, st.guess);
  if (pose.x.allFinite()) st.guess = pose.x;
  rec.flags |= telemetry::kFlagStepped;
  rec.position = in.q[0];
  rec.joint_position[0] = in.q[1];
  rec.joint_position[1] = in.q[2];
  const bool placed = st.guess.allFinite();  // a pose found, now or on an earlier tick
  for (int i = 0; i < 3; ++i) rec.task_position[i] = placed ? st.guess[i] : 0.0;
  rec.pose_status = static_cast<std::uint8_t>(pose.status);

  control::SceneStep step;
  st.walls->scene->step_walls(pose, step);
  record_walls(*st.walls->scene, step, rec);
  JointCommand c;
  double energy = st.walls->ended.energy_j;  // the walls a reload ended still count
  for (std::size_t i = 0; i < step.count; ++i) {
    control::PassivityObserver& o = st.walls->observers[i];
    o.observe(step.channels[i].penetration, in.fresh, in.periods);  // s_i: the law's penetration
    energy += o.energy_j();
    const control::Damping d = o.damp(step.channels[i].force_commanded, st.walls->scene->law(i));
    c.channel[i] = d.command;
    c.added[i] = d.added;
    if (d.alpha > 0.0) {
      rec.flags |= telemetry::kFlagPassivityDamped;
      rec.passivity_damping = std::max(rec.passivity_damping, d.alpha);
    }
  }
  rec.observer_energy_j = energy;
  for (int a = 0; a < 3; ++a) rec.client_force[a] = in.client_force[a];
  st.walls->scene->map(pose, std::span<const double>(c.channel.data(), step.count), st.limit, step,
                       in.client_force);
  rec.flags |= step.flags;  // the joints' saturation, a non-finite torque
  c.non_finite = (step.flags & control::kControlNonFinite) != 0;
  c.runaway = running_away(st, step, rec.penetration, rec.deepest_wall);
  if (c.runaway) rec.flags |= telemetry::kFlagRunaway;
  c.pose_fault = !step.pose_ok;
  c.scale = step.scale;
  if (!c.faulted()) {
    c.tau = step.tau;
    c.force = step.scale * step.force;
  }
  return c;
}

void end_scene_tick(SceneState& st, const JointCommand* c, telemetry::TickRecord& rec) noexcept {
  const Vec3 tau = c != nullptr ? c->tau : Vec3::Zero();
  rec.force_commanded = tau[0];
  rec.joint_force[0] = tau[1];
  rec.joint_force[1] = tau[2];
  const bool acted = c != nullptr && !c->faulted();
  for (std::size_t i = 0; i < st.walls->observers.size(); ++i) {
    // What acted along the channel: its force, scaled with the joints' saturation.
    st.walls->observers[i].commanded(acted ? c->scale * c->channel[i] : 0.0,
                                     acted ? c->scale * c->added[i] : 0.0);
  }
}

}  // namespace hapticd::loop
