// The section device.kinematics: which mechanism the joints drive and its numbers
// (docs/kinematics.md). Each kind reads only its own keys; another kind's key is refused, not
// ignored, and what the numbers describe is checked by the kinematics' own rule
// (kinematics::invalid_reason), so the file and the code cannot disagree on what is valid.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "base/joints.h"
#include "config/config_schema.h"

namespace hapticd::config::schema {
namespace {

using kinematics::Vec3;
using KinematicsKind = kinematics::Kind;

const Options<KinematicsKind> kKinematicsKinds{{"joints", KinematicsKind::kJoints},
                                               {"cartesian", KinematicsKind::kCartesian},
                                               {"pantograph", KinematicsKind::kPantograph},
                                               {"delta", KinematicsKind::kDelta}};

// Each kind's keys; a key of another kind is refused by name.
const std::vector<std::pair<KinematicsKind, std::vector<std::string>>> kKinematicsKeys{
    {KinematicsKind::kJoints, {"joints", "workspace"}},
    {KinematicsKind::kCartesian, {"joints", "scale", "sign", "workspace"}},
    {KinematicsKind::kPantograph, {"proximal", "distal", "base_separation", "workspace"}},
    {KinematicsKind::kDelta,
     {"thigh", "shin", "effector_u", "effector_v", "effector_joint", "knee_joint", "base_u",
      "base_v", "arm_angle_deg", "home", "workspace"}},
};

void read_vec3(MapReader& m, std::string_view key, int n, const Range& range, Vec3& out) {
  read_fixed_numbers(m, key, n, range, out.data());
}

// The workspace: a box on the task coordinates (m), or on the joints' own for `joints`.
void read_workspace(MapReader& parent, int m, kinematics::Box& box) {
  const Field f = parent.take("workspace");
  if (!f.present) return;
  MapReader w(parent.diag(), f);
  read_vec3(w, "lower", m, Range::any(), box.lower);
  read_vec3(w, "upper", m, Range::any(), box.upper);
  w.finish();
}

bool is_sign(double v, const Range&) { return v == 1.0 || v == -1.0; }

void read_delta(MapReader& m, kinematics::DeltaParams& d) {
  const Range length = Range::greater_than(0.0);
  number(m, "thigh", length, d.thigh);
  number(m, "shin", length, d.shin);
  number(m, "effector_u", Range::any(), d.effector_u);
  number(m, "effector_v", Range::any(), d.effector_v);
  number(m, "effector_joint", Range::any(), d.effector_joint);
  number(m, "knee_joint", Range::any(), d.knee_joint);
  number(m, "base_u", Range::any(), d.base_u);
  number(m, "base_v", Range::any(), d.base_v);
  double deg[3];
  for (int i = 0; i < 3; ++i) deg[i] = d.arm_angle[i] * 180.0 / std::numbers::pi;
  read_fixed_numbers(m, "arm_angle_deg", 3, Range::any(), deg);
  for (int i = 0; i < 3; ++i) d.arm_angle[i] = deg[i] * std::numbers::pi / 180.0;
  read_vec3(m, "home", 3, Range::any(), d.home);
  read_workspace(m, 3, d.workspace);
}

}  // namespace

bool read_fixed_numbers(MapReader& m, const Field& f, int n, bool (*ok)(double, const Range&),
                        const Range& range, const std::string& what, double* out,
                        const std::string& entries) {
  const auto list = read_number_list(m.diag(), f);
  if (!list) return false;
  if (static_cast<int>(list->size()) != n) {
    m.diag().error(
        f.key_mark, f.path,
        "must hold " + std::to_string(n) + " " + entries + ", got " + std::to_string(list->size()));
    return false;
  }
  for (int i = 0; i < n; ++i) {
    const double v = (*list)[static_cast<std::size_t>(i)];
    if (!ok(v, range)) {
      m.diag().error(f.key_mark, f.path + "[" + std::to_string(i) + "]",
                     "must be " + what + ", got " + format_number(v));
      return false;
    }
  }
  for (int i = 0; i < n; ++i) out[i] = (*list)[static_cast<std::size_t>(i)];
  return true;
}

bool read_fixed_numbers(MapReader& m, std::string_view key, int n, const Range& range, double* out,
                        const std::string& entries) {
  return read_fixed_numbers(
      m, m.take(key), n, [](double v, const Range& r) { return r.contains(v); }, range,
      range.describe(), out, entries);
}

void read_kinematics(MapReader& device, kinematics::Kinematics& k) {
  const Field f = device.take("kinematics");
  if (!f.present) return;  // one joint: today's axis
  MapReader m(device.diag(), f);
  if (!m.ok()) return;
  if (const auto kind = choice(m.diag(), m.take("kind"), kKinematicsKinds)) k.kind = *kind;
  const std::size_t errors_before = m.diag().messages().size();
  const std::vector<std::string>* own = nullptr;
  for (const auto& [kind, keys] : kKinematicsKeys) {
    if (kind == k.kind) own = &keys;
  }
  for (const auto& [kind, keys] : kKinematicsKeys) {
    for (const std::string& key : keys) {
      if (std::find(own->begin(), own->end(), key) == own->end()) {
        m.not_used(key, "device.kinematics.kind " + name_of(kKinematicsKinds, k.kind));
      }
    }
  }
  const IntRange joints = IntRange::between(1, static_cast<long long>(base::kMaxJoints));
  switch (k.kind) {
    case KinematicsKind::kJoints:
      integer(m, "joints", joints, k.joints.n);
      read_workspace(m, k.joints.n, k.joints.workspace);
      break;
    case KinematicsKind::kCartesian:
      integer(m, "joints", joints, k.cartesian.n);
      read_vec3(m, "scale", k.cartesian.n, Range::greater_than(0.0), k.cartesian.scale);
      read_fixed_numbers(m, m.take("sign"), k.cartesian.n, &is_sign, Range::any(), "+1 or -1",
                         k.cartesian.sign.data());
      read_workspace(m, k.cartesian.n, k.cartesian.workspace);
      break;
    case KinematicsKind::kPantograph:
      read_fixed_numbers(m, "proximal", 2, Range::greater_than(0.0), k.pantograph.proximal);
      read_fixed_numbers(m, "distal", 2, Range::greater_than(0.0), k.pantograph.distal);
      number(m, "base_separation", Range::greater_than(0.0), k.pantograph.base_separation);
      read_workspace(m, 2, k.pantograph.workspace);
      break;
    case KinematicsKind::kDelta:
      read_delta(m, k.delta);
      break;
  }
  m.finish();
  if (m.diag().messages().size() != errors_before) return;
  if (const char* why = kinematics::invalid_reason(k)) {
    m.diag().error(f.key_mark, f.path, std::string("describes no mechanism: ") + why);
  }
}

}  // namespace hapticd::config::schema
