// The gate over a workspace as `hapticd check` shows it: per wall its demand, the least damping
// the device has along its normal (an attractor: in any direction) and where, the largest stiffness
// that passes there; then the walls acting together and what the sampling measured.
#include <cmath>

#include "gate/gate_report_format.h"
#include "gate/number_format.h"
#include "kinematics/kinematics.h"

namespace hapticd::gate {
namespace {

using json = nlohmann::json;

json position(const kinematics::Vec3& x, int m) {
  json a = json::array();
  for (int i = 0; i < m; ++i) a.push_back(x[i]);
  return a;
}

std::string position_text(const kinematics::Vec3& x, int m) {
  std::string s = "(";
  for (int i = 0; i < m; ++i) s += (i ? ", " : "") + format_number(x[i] * 1e3);
  return s + ") mm";
}

}  // namespace

json workspace_to_json(const WorkspaceReport& w) {
  json walls = json::array();
  const int m = 3;  // positions carry every task axis; the unused ones are 0
  for (const WallVerdict& v : w.walls) {
    walls.push_back({{"required_damping", finite_or_null(v.required_damping)},
                     {"available_damping", finite_or_null(v.available_damping)},
                     {"normal_damping", finite_or_null(v.worst_damping)},
                     {"grid_normal_damping", finite_or_null(v.grid_worst_damping)},
                     {"worst_position", position(v.worst_position, m)},
                     {"reached", v.reached},
                     {"passive", v.passive},
                     {"max_stiffness",
                      v.reached && v.max_stiffness.kind == analysis::StiffnessLimit::Kind::kBounded
                          ? json(v.max_stiffness.value)
                          : json(nullptr)}});
  }
  return {{"walls", walls},
          {"joint_damping", w.joint_damping},
          {"samples", w.samples},
          {"outside", w.outside},
          {"corner_margin", finite_or_null(w.corner_margin)},
          {"corner_position",
           std::isfinite(w.corner_margin) ? position(w.corner_position, m) : json(nullptr)},
          {"neighbour_change", w.neighbour_change},
          {"configuration_independent", w.configuration_independent},
          {"pass", w.pass},
          {"movable", w.movable},
          {"not_movable", w.movable ? json(nullptr) : json(w.not_movable)}};
}

void workspace_rows(const WorkspaceReport& w, const config::Config& cfg, std::ostream& os) {
  const int m = kinematics::joint_count(cfg.device.kinematics);
  os << "passivity along each wall's normal over the workspace (docs/math.md, several axes)\n";
  os << "  workspace                 " << w.samples << " samples ("
     << (w.configuration_independent ? "J the same everywhere"
                                     : std::to_string(w.outside) + " not a pose")
     << "), largest change of b_n between neighbours " << format_number(w.neighbour_change * 100, 3)
     << " %\n";
  for (std::size_t i = 0; i < w.walls.size(); ++i) {
    const WallVerdict& v = w.walls[i];
    os << "  walls[" << i << "]                  ";
    if (!v.reached) {
      os << "never reached in the workspace\n";
      continue;
    }
    const bool attractor = cfg.walls[i].kind == config::WallKind::kAttractor;
    os << (attractor ? "attractor, " : "") << "b_req " << format_number(v.required_damping)
       << " <= " << format_number(v.available_damping) << " N s/m? " << (v.passive ? "yes" : "NO")
       << (attractor ? " (lambda_min(B_c) " : " (b_n ") << format_number(v.worst_damping) << " at "
       << position_text(v.worst_position, m) << "; largest passing K "
       << (v.max_stiffness.kind == analysis::StiffnessLimit::Kind::kBounded
               ? format_number(v.max_stiffness.value) + " N/m"
               : stiffness_note(v.max_stiffness))
       << ", configured " << format_number(cfg.walls[i].law.stiffness) << ")\n";
  }
  os << "  walls acting together     "
     << (std::isfinite(w.corner_margin) ? "least eigenvalue " + format_number(w.corner_margin) +
                                              " N s/m at " + position_text(w.corner_position, m)
                                        : std::string("none meet in the workspace"))
     << "\n";
  os << "  moved by clients          "
     << (w.movable ? std::string("anywhere in the workspace, with no new gate")
                   : "each move refused: " + w.not_movable)
     << "\n";
}

}  // namespace hapticd::gate
