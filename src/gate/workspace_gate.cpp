#include "gate/workspace_gate.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/normal_passivity.h"
#include "analysis/wall_model.h"
#include "control/control_law.h"
#include "gate/number_format.h"
#include "kinematics/kinematics.h"

namespace hapticd::gate {
namespace {

using kinematics::Vec3;
constexpr double kInf = std::numeric_limits<double>::infinity();

// The device at task position x (its pose through inverse, then forward kinematics): the
// status of the first that is not kOk, where x is not a pose of the mechanism.
kinematics::Status pose_at(const config::Config& cfg, const Vec3& x, analysis::DeviceDamping& d) {
  const kinematics::Kinematics& k = cfg.device.kinematics;
  const kinematics::JointSolution q = kinematics::inverse(k, x);
  if (q.status != kinematics::Status::kOk) return q.status;
  const kinematics::Pose p = kinematics::forward(k, q.q, x);
  if (p.status != kinematics::Status::kOk) return p.status;
  d.jacobian = p.J;
  d.joint_damping = cfg.device.damping.per_joint();
  d.m = p.m;
  d.n = p.n;
  return kinematics::Status::kOk;
}

bool device_at(const config::Config& cfg, const Vec3& x, analysis::DeviceDamping& d) {
  return pose_at(cfg, x, d) == kinematics::Status::kOk;
}

// The configuration that runs wall w's law: its own section on the coordinate along n.
config::Config wall_config(const config::Config& cfg, const config::TaskWallConfig& w) {
  config::Config c = cfg;
  c.wall = w.law;
  c.wall.position = 0.0;
  c.wall.normal = 1;
  return c;
}

analysis::TransferFunction contact(const config::Config& c, double k) {
  return analysis::contact_map(analysis::environment_filter(control::wall_params(c, k)),
                               control::coupling_filter(c));
}

std::string point_text(const Vec3& x, int m) {
  std::string s = "(";
  for (int i = 0; i < m; ++i) s += (i ? ", " : "") + format_number(x[i]);
  return s + ") m";
}

// The sampled workspace: every grid point's device, or none where it is not a pose.
struct Grid {
  int m = 1;
  int per_axis = 1;
  Vec3 lower = Vec3::Zero();
  Vec3 cell = Vec3::Zero();
  double reach = 0.0;  // a cell's diagonal: how far from a face a sample still counts
  std::vector<Vec3> x;
  std::vector<bool> ok;
  std::vector<analysis::DeviceDamping> device;
  std::size_t first_bad = 0;  // the first sample that is not a pose, if any
  kinematics::Status first_bad_status = kinematics::Status::kOk;
};

Grid sample(const config::Config& cfg, const kinematics::Box& box, int m) {
  Grid g;
  g.m = m;
  g.per_axis = kWorkspaceSamples;
  int total = 1;
  for (int a = 0; a < m; ++a) total *= g.per_axis;
  for (int a = 0; a < m; ++a) {
    // The outermost samples sit a billionth of the box inside its faces: a point exactly on a
    // face can come back from inverse and forward kinematics a rounding error outside it.
    const double extent = box.upper[a] - box.lower[a], inset = 1e-9 * extent;
    g.lower[a] = box.lower[a] + inset;
    g.cell[a] = (extent - 2.0 * inset) / (g.per_axis - 1);
  }
  g.reach = g.cell.head(m).norm();
  for (int i = 0; i < total; ++i) {
    Vec3 x = Vec3::Zero();
    for (int a = 0, r = i; a < m; ++a, r /= g.per_axis)
      x[a] = g.lower[a] + (r % g.per_axis) * g.cell[a];
    analysis::DeviceDamping d;
    const kinematics::Status st = pose_at(cfg, x, d);
    if (st != kinematics::Status::kOk && g.first_bad_status == kinematics::Status::kOk) {
      g.first_bad = g.x.size();
      g.first_bad_status = st;
    }
    g.ok.push_back(st == kinematics::Status::kOk);
    g.x.push_back(x);
    g.device.push_back(d);
  }
  return g;
}

bool attractor(const config::TaskWallConfig& w) { return w.kind == config::WallKind::kAttractor; }

// How deep x is in wall w; an attractor acts everywhere.
double depth(const config::TaskWallConfig& w, const Vec3& x) {
  return attractor(w) ? kInf : w.normal.dot(x - w.point);
}

// The least damping the device has where wall w acts, along the way the wall pushes: b_n along
// a wall's normal; an attractor pushes every way, so the least of them, lambda_min(B_c).
double damping_for(const config::TaskWallConfig& w, const analysis::DeviceDamping& d) {
  return attractor(w) ? std::max(0.0, analysis::contact_margin(d, {}))
                      : analysis::normal_damping(d, w.normal);
}

// Wall w's demands on B_c (`required`: its b_req over the margin kept): b_req along its normal;
// an attractor's along each task axis, b_req I in all (its axes' laws each need b_req).
void add_demands(const config::TaskWallConfig& w, double required, int m,
                 std::vector<analysis::NormalDemand>& demands) {
  if (!attractor(w)) {
    demands.push_back({w.normal, required});
    return;
  }
  for (int k = 0; k < m; ++k) demands.push_back({Vec3::Unit(k), required});
}

// Where to sample a mechanism whose Jacobian is the same everywhere and whose workspace is
// unbounded: only which walls act together depends on x, so a box around the walls' points,
// grown by their extent (at least 1 cm) each way, holds every edge and corner they make.
kinematics::Box around_walls(const std::vector<config::TaskWallConfig>& walls, int m) {
  kinematics::Box b;
  b.lower = Vec3::Constant(kInf);
  b.upper = Vec3::Constant(-kInf);
  for (const config::TaskWallConfig& w : walls) {
    b.lower = b.lower.cwiseMin(w.point);
    b.upper = b.upper.cwiseMax(w.point);
  }
  for (int a = 0; a < m; ++a) {
    if (walls.empty()) b.lower[a] = b.upper[a] = 0.0;
    const double grow = std::max(b.upper[a] - b.lower[a], 0.01);
    b.lower[a] -= grow;
    b.upper[a] += grow;
  }
  return b;
}

// Pattern search from `best` for a lower b_n where wall w acts (`anywhere`: wherever it could
// be moved to): each axis both ways, the step halved when nothing is lower, down to 1e-4 of a
// cell.
void refine(const config::Config& cfg, const config::TaskWallConfig& w, const Grid& g,
            WallVerdict& v, bool anywhere = false) {
  const Vec3 upper = g.lower + (g.per_axis - 1) * g.cell;
  Vec3 step = 0.5 * g.cell;
  const Vec3 stop = 1e-4 * g.cell;
  for (int evaluations = 0;
       evaluations < 2000 && (step.head(g.m).array() > stop.head(g.m).array()).any();) {
    bool moved = false;
    for (int a = 0; a < g.m && !moved; ++a) {
      for (const double sign : {-1.0, 1.0}) {
        Vec3 y = v.worst_position;
        y[a] += sign * step[a];
        ++evaluations;
        analysis::DeviceDamping d;
        if (y[a] < g.lower[a] || y[a] > upper[a] || (!anywhere && depth(w, y) < -g.reach) ||
            !device_at(cfg, y, d)) {
          continue;
        }
        const double b = damping_for(w, d);
        if (b < v.worst_damping) {
          v.worst_damping = b;
          v.worst_position = y;
          moved = true;
          break;
        }
      }
    }
    if (!moved) step *= 0.5;
  }
}

// Wall i alone: its b_req and the least b_n where it acts.
WallVerdict judge_wall(const config::Config& cfg, const config::TaskWallConfig& w, int delay,
                       const Grid& g, double& neighbour_change) {
  WallVerdict v;
  const config::Config c = wall_config(cfg, w);
  const double t = cfg.loop.sample_period_s(), eta = cfg.safety.operator_passivity_shortage;
  const int d = w.law.delay_samples + delay;
  v.required_damping =
      analysis::passivity_bound(contact(c, w.law.stiffness), t, d, eta).required_damping;
  v.worst_damping = kInf;
  std::vector<double> b(g.x.size(), kInf);
  for (std::size_t i = 0; i < g.x.size(); ++i) {
    if (!g.ok[i] || depth(w, g.x[i]) < -g.reach) continue;
    v.reached = true;
    b[i] = damping_for(w, g.device[i]);
    if (b[i] < v.worst_damping) {
      v.worst_damping = b[i];
      v.worst_position = g.x[i];
    }
  }
  v.grid_worst_damping = v.worst_damping;
  if (v.reached) {
    for (std::size_t i = 0; i < g.x.size(); ++i) {
      for (int a = 0, stride = 1; a < g.m; ++a, stride *= g.per_axis) {
        const std::size_t j = i + static_cast<std::size_t>(stride);
        if ((static_cast<int>(i) / stride) % g.per_axis == g.per_axis - 1) continue;
        if (std::isfinite(b[i]) && std::isfinite(b[j]) && std::min(b[i], b[j]) > 0.0) {
          neighbour_change =
              std::max(neighbour_change, std::abs(b[i] - b[j]) / std::min(b[i], b[j]));
        }
      }
    }
    refine(cfg, w, g, v);
  }
  v.available_damping = (1.0 - cfg.safety.passivity_margin) * v.worst_damping;
  v.passive = !v.reached ||
              (std::isfinite(v.required_damping) && v.required_damping <= v.available_damping);
  if (v.reached && std::isfinite(v.available_damping)) {
    v.max_stiffness = analysis::max_stiffness([&](double k) { return contact(c, k); }, t, d, eta,
                                              v.available_damping);
  }
  return v;
}

// Walls acting together: the least matrix margin over the samples where two or more act (an
// attractor's axes are as many walls, acting everywhere).
void judge_corners(const config::Config& cfg, const Grid& g, WorkspaceReport& r) {
  r.corner_margin = kInf;
  const double keep = 1.0 - cfg.safety.passivity_margin;
  std::vector<analysis::NormalDemand> demands;
  for (std::size_t i = 0; i < g.x.size(); ++i) {
    if (!g.ok[i]) continue;
    demands.clear();
    for (std::size_t w = 0; w < cfg.walls.size(); ++w) {
      if (depth(cfg.walls[w], g.x[i]) < -g.reach) continue;
      add_demands(cfg.walls[w], r.walls[w].required_damping / keep, g.m, demands);
    }
    if (demands.size() < 2) continue;
    const double margin = analysis::contact_margin(g.device[i], demands);
    if (!(margin >= r.corner_margin)) {
      r.corner_margin = margin;
      r.corner_position = g.x[i];
    }
  }
}

// Whether the walls may be moved anywhere without a new gate (scene moves): each wall's b_req
// against the least b_n over the whole workspace, and every wall acting at once at every
// sample (moved walls can meet anywhere, even overlap). Only for walls that pass where they are.
void judge_movable(const config::Config& cfg, const Grid& g, WorkspaceReport& r) {
  const double keep = 1.0 - cfg.safety.passivity_margin;
  const auto refuse = [&](std::string why) {
    r.movable = false;
    r.not_movable = std::move(why);
  };
  r.movable = true;
  if (!r.pass) return refuse("the gate refuses the walls where they are");
  std::vector<analysis::NormalDemand> demands;
  for (std::size_t i = 0; i < cfg.walls.size(); ++i) {
    const config::TaskWallConfig& w = cfg.walls[i];
    WallVerdict v = r.walls[i];
    v.worst_damping = kInf;
    for (std::size_t k = 0; k < g.x.size(); ++k) {
      const double b = damping_for(w, g.device[k]);
      if (b < v.worst_damping) {
        v.worst_damping = b;
        v.worst_position = g.x[k];
      }
    }
    refine(cfg, w, g, v, /*anywhere=*/true);
    add_demands(w, v.required_damping / keep, g.m, demands);
    if (v.required_damping <= keep * v.worst_damping) continue;
    return refuse("walls[" + std::to_string(i) + "]: b_req " + format_number(v.required_damping) +
                  " exceeds (1 - " + format_number(cfg.safety.passivity_margin) + ") " +
                  (attractor(w) ? "lambda_min(B_c)" : "b_n") + " = " +
                  format_number(keep * v.worst_damping) +
                  " at x = " + point_text(v.worst_position, g.m) + ", where it could be moved to");
  }
  if (demands.size() < 2) return;
  for (std::size_t k = 0; k < g.x.size(); ++k) {
    const double margin = analysis::contact_margin(g.device[k], demands);
    if (margin >= 0.0) continue;
    return refuse("every wall acting at once at x = " + point_text(g.x[k], g.m) +
                  ", where moved walls could meet: B_c - sum b_req_i / (1 - margin) n_i n_i^T has "
                  "least eigenvalue " +
                  format_number(margin) + " < 0");
  }
}

// An attractor whose point the device cannot reach would hold it against the mechanism's
// limits with its whole force: refused, where the workspace says what can be reached.
void refuse_attractors_outside(const config::Config& cfg, const kinematics::Box& box, int m,
                               WorkspaceReport& r) {
  for (std::size_t i = 0; i < cfg.walls.size(); ++i) {
    const config::TaskWallConfig& w = cfg.walls[i];
    if (!attractor(w)) continue;
    bool inside = true;
    for (int a = 0; a < m; ++a) {
      inside = inside && w.point[a] >= box.lower[a] && w.point[a] <= box.upper[a];
    }
    if (inside) continue;
    r.reasons.push_back("walls[" + std::to_string(i) + "]: an attractor's point " +
                        point_text(w.point, m) +
                        " lies outside device.kinematics.workspace: it would hold the device "
                        "against the mechanism's limits with its whole force");
  }
}

}  // namespace

WorkspaceReport evaluate_workspace(const config::Config& cfg, int device_delay_samples) {
  WorkspaceReport r;
  const kinematics::Kinematics& k = cfg.device.kinematics;
  const int m = kinematics::joint_count(k);
  for (int j = 0; j < m; ++j)
    r.joint_damping.push_back(cfg.device.damping[static_cast<std::size_t>(j)]);
  const kinematics::Box& box = kinematics::workspace(k);
  r.configuration_independent =
      k.kind == kinematics::Kind::kJoints || k.kind == kinematics::Kind::kCartesian;
  bool finite = true;
  for (int a = 0; a < m; ++a) {
    finite = finite && std::isfinite(box.lower[a]) && std::isfinite(box.upper[a]);
  }
  if (!r.configuration_independent && !finite) {
    r.reasons.push_back("device.kinematics.workspace: a " +
                        std::string(kinematics::kind_name(k.kind)) +
                        "'s damping along a normal depends on where it is: its workspace must be "
                        "a finite box to be proven over");
    return r;
  }
  const Grid g = sample(cfg, finite ? box : around_walls(cfg.walls, m), m);
  r.samples = static_cast<int>(g.x.size());
  r.outside = static_cast<int>(std::count(g.ok.begin(), g.ok.end(), false));
  // The workspace is where the device renders: a box that claims configurations the mechanism
  // cannot take (out of reach, near a singularity) is a wrong box, and a grid mostly outside
  // the mechanism would prove nothing of it.
  if (r.outside > 0) {
    r.reasons.push_back("device.kinematics.workspace: " + std::to_string(r.outside) + " of " +
                        std::to_string(r.samples) +
                        " sampled configurations are not a pose of the mechanism (the first at x "
                        "= " +
                        point_text(g.x[g.first_bad], m) + ": " +
                        kinematics::status_name(g.first_bad_status) +
                        "); the workspace must lie where the mechanism works to be proven over");
    return r;
  }
  for (std::size_t i = 0; i < cfg.walls.size(); ++i) {
    r.walls.push_back(judge_wall(cfg, cfg.walls[i], device_delay_samples, g, r.neighbour_change));
    const WallVerdict& v = r.walls.back();
    if (v.passive) continue;
    const std::string wall = "walls[" + std::to_string(i) + "]";
    const bool pulls = attractor(cfg.walls[i]);
    const std::string b = pulls ? "lambda_min(B_c)" : "b_n";
    std::string why =
        wall + (pulls ? " (an attractor)" : "") + ": b_req " + format_number(v.required_damping) +
        " exceeds (1 - " + format_number(cfg.safety.passivity_margin) + ") " + b + " = " +
        format_number(v.available_damping) + ", " + b + " = " + format_number(v.worst_damping) +
        " the least damping the device has " + (pulls ? "in any direction" : "along its normal") +
        " (at x = " + point_text(v.worst_position, m) + ")";
    if (v.max_stiffness.kind == analysis::StiffnessLimit::Kind::kBounded) {
      why += "; " + wall + ".stiffness must be <= " + format_number(v.max_stiffness.value) +
             " to pass (now " + format_number(cfg.walls[i].law.stiffness) + ")";
    }
    r.reasons.push_back(why);
  }
  if (finite) refuse_attractors_outside(cfg, box, m, r);
  judge_corners(cfg, g, r);
  if (r.corner_margin < 0.0 || std::isnan(r.corner_margin)) {
    r.reasons.push_back("walls acting together at x = " + point_text(r.corner_position, m) +
                        ": B_c - sum b_req_i / (1 - margin) n_i n_i^T has least eigenvalue " +
                        format_number(r.corner_margin) + " < 0 (docs/math.md, several axes)");
  }
  r.pass = r.reasons.empty();
  judge_movable(cfg, g, r);
  return r;
}

}  // namespace hapticd::gate
