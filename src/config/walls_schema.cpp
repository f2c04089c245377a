// The section `walls`: the task-space walls of a device with several task axes
// (docs/kinematics.md, walls in task space). Each is a point, a normal into the wall and the
// contact law `wall` has, or (kind: attractor) a point and that law along every task axis,
// bilateral; a list of at most kMaxWalls.
#include <cmath>
#include <string>
#include <vector>

#include "config/config_schema.h"

namespace hapticd::config::schema {
namespace {

constexpr const char* kPerAxis = "numbers (one per task axis)";
const Options<WallKind> kWallKinds{{"wall", WallKind::kWall}, {"attractor", WallKind::kAttractor}};

// `point` or `normal` of a wall (`f`, its field `key`): both are needed.
bool task_vector(MapReader& w, const Field& f, std::string_view key, int m, kinematics::Vec3& out) {
  if (f.present) {
    return read_fixed_numbers(
        w, f, m, [](double, const Range&) { return true; }, Range::any(), "", out.data(), kPerAxis);
  }
  w.missing(key, "every wall has a point and a normal");
  return false;
}

}  // namespace

bool unit_direction(Diagnostics& d, const Field& f, const std::string& what, kinematics::Vec3& v) {
  // Only where it points counts (the docs say so). Scaled by its largest entry first, so
  // neither 1e300 nor 1e-320 over- or underflows on the way to unit.
  const double largest = v.cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) {
    d.error(f.key_mark, f.path, "must point somewhere (" + what + "), got all zeros");
    return false;
  }
  v /= largest;
  v /= v.norm();
  return true;
}

void read_walls(MapReader& top, int task_axes, std::vector<TaskWallConfig>& walls) {
  const Field f = top.take("walls");
  if (!f.present || f.node.IsNull()) return;
  Diagnostics& d = top.diag();
  if (!f.node.IsSequence()) {
    d.error(f.key_mark, f.path, "must be a list of walls, got " + describe_value(f.node));
    return;
  }
  if (f.node.size() > kMaxWalls) {
    d.error(
        f.key_mark, f.path,
        "at most " + std::to_string(kMaxWalls) + " walls, got " + std::to_string(f.node.size()));
    return;
  }
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    const YAML::Node node = f.node[i];
    const Field entry{f.path + "[" + std::to_string(i) + "]", node, node.Mark(), true};
    MapReader w(d, entry);
    if (!w.ok()) continue;
    TaskWallConfig wall;
    if (const auto v = choice(d, w.take("kind"), kWallKinds)) wall.kind = *v;
    const bool point = task_vector(w, w.take("point"), "point", task_axes, wall.point);
    bool normal = true;
    read_wall_law(w, wall.law);
    if (wall.kind == WallKind::kAttractor) {
      w.not_used("normal", "an attractor: it pulls towards its point along every task axis");
      const Field pull = w.take("no_pull");
      if (pull.present && wall.law.no_pull) {
        d.error(pull.key_mark, pull.path,
                "an attractor pulls towards its point: no_pull: true "
                "would leave half of it; use a wall");
      }
      number(w, "max_force", Range::greater_than(0.0), wall.max_force);
    } else {
      const Field normal_field = w.take("normal");
      normal = task_vector(w, normal_field, "normal", task_axes, wall.normal) &&
               unit_direction(d, normal_field, "a direction into the wall", wall.normal);
      w.not_used("max_force",
                 "a wall (the joints' device.max_force limits it; an attractor's "
                 "own limit)");
    }
    w.finish();
    if (point && normal) walls.push_back(std::move(wall));
  }
}

}  // namespace hapticd::config::schema
