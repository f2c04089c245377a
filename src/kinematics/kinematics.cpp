#include "kinematics/kinematics.h"

#include <cmath>

namespace hapticd::kinematics {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0; }

// Lower below upper on the first m coordinates (an infinite bound is allowed).
bool box_valid(const Box& b, int m) {
  for (int i = 0; i < m; ++i) {
    if (!(b.lower[i] < b.upper[i])) return false;
  }
  return true;
}

bool size_valid(int n) { return n >= 1 && n <= 3; }

bool thresholds_valid(const SingularityThresholds& t) {
  return t.min_inverse_condition >= 0 && t.min_inverse_condition <= 1 &&
         t.min_singular_value >= 0 && std::isfinite(t.min_singular_value);
}

const char* cartesian_invalid(const CartesianParams& p) {
  if (!size_valid(p.n)) return "cartesian: n must be 1, 2 or 3";
  for (int i = 0; i < p.n; ++i) {
    if (!positive(p.scale[i])) return "cartesian: every scale must be positive";
    if (p.sign[i] != 1.0 && p.sign[i] != -1.0) return "cartesian: every sign must be +1 or -1";
  }
  return box_valid(p.workspace, p.n) ? nullptr : "cartesian: empty workspace box";
}

const char* pantograph_invalid(const PantographParams& p) {
  for (int i = 0; i < 2; ++i) {
    if (!positive(p.proximal[i]) || !positive(p.distal[i])) {
      return "pantograph: link lengths must be positive";
    }
  }
  if (!positive(p.base_separation)) return "pantograph: base separation must be positive";
  if (!thresholds_valid(p.near)) return "pantograph: singularity thresholds must be >= 0";
  return box_valid(p.workspace, 2) ? nullptr : "pantograph: empty workspace box";
}

const char* delta_invalid(const DeltaParams& p) {
  if (!positive(p.thigh) || !positive(p.shin)) return "delta: thigh and shin must be positive";
  if (p.max_iterations < 1) return "delta: max_iterations must be at least 1";
  if (!positive(p.tolerance)) return "delta: tolerance must be positive";
  if (!thresholds_valid(p.near)) return "delta: singularity thresholds must be >= 0";
  return box_valid(p.workspace, 3) ? nullptr : "delta: empty workspace box";
}

}  // namespace

const char* kind_name(Kind k) noexcept {
  switch (k) {
    case Kind::kJoints:
      return "joints";
    case Kind::kCartesian:
      return "cartesian";
    case Kind::kPantograph:
      return "pantograph";
    case Kind::kDelta:
      return "delta";
  }
  return "unknown";
}

int joint_count(const Kinematics& k) noexcept {
  switch (k.kind) {
    case Kind::kJoints:
      return k.joints.n;
    case Kind::kCartesian:
      return k.cartesian.n;
    case Kind::kPantograph:
      return 2;
    case Kind::kDelta:
      return 3;
  }
  return 0;
}

const Box& workspace(const Kinematics& k) noexcept {
  switch (k.kind) {
    case Kind::kJoints:
      return k.joints.workspace;
    case Kind::kCartesian:
      return k.cartesian.workspace;
    case Kind::kPantograph:
      return k.pantograph.workspace;
    case Kind::kDelta:
      return k.delta.workspace;
  }
  return k.joints.workspace;
}

Box& workspace(Kinematics& k) noexcept {
  return const_cast<Box&>(workspace(static_cast<const Kinematics&>(k)));
}

Vec3 workspace_centre(const Kinematics& k) noexcept {
  const Box& b = workspace(k);
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < joint_count(k); ++i) {
    if (std::isfinite(b.lower[i]) && std::isfinite(b.upper[i]))
      c[i] = 0.5 * (b.lower[i] + b.upper[i]);
  }
  return c;
}

const char* invalid_reason(const Kinematics& k) noexcept {
  switch (k.kind) {
    case Kind::kJoints:
      if (!size_valid(k.joints.n)) return "joints: n must be 1, 2 or 3";
      return box_valid(k.joints.workspace, k.joints.n) ? nullptr : "joints: empty joint ranges";
    case Kind::kCartesian:
      return cartesian_invalid(k.cartesian);
    case Kind::kPantograph:
      return pantograph_invalid(k.pantograph);
    case Kind::kDelta:
      return delta_invalid(k.delta);
  }
  return "unknown kind";
}

Pose forward(const Kinematics& k, const Vec3& q, const Vec3& guess) noexcept {
  switch (k.kind) {
    case Kind::kJoints:
      return joints_forward(k.joints, q);
    case Kind::kCartesian:
      return cartesian_forward(k.cartesian, q);
    case Kind::kPantograph:
      return pantograph_forward(k.pantograph, q);
    case Kind::kDelta:
      return delta_forward(k.delta, q, guess);
  }
  return Pose{Status::kNoConvergence};
}

JointSolution inverse(const Kinematics& k, const Vec3& x) noexcept {
  switch (k.kind) {
    case Kind::kJoints:
      return joints_inverse(k.joints, x);
    case Kind::kCartesian:
      return cartesian_inverse(k.cartesian, x);
    case Kind::kPantograph:
      return pantograph_inverse(k.pantograph, x);
    case Kind::kDelta:
      return delta_inverse(k.delta, x);
  }
  return JointSolution{Status::kOutsideWorkspace};
}

}  // namespace hapticd::kinematics
