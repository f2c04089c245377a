#include "kinematics/delta.h"

#include <Eigen/LU>
#include <cmath>

#include "kinematics/conditioning.h"

namespace hapticd::kinematics {
namespace {

// One arm at a task position: its joint angle and the derivatives of its closure constraint.
struct Arm {
  bool reachable = false;
  double q = 0.0;
  Eigen::RowVector3d dg_dx = Eigen::RowVector3d::Zero();
  double dg_dq = 0.0;
};

Arm solve_arm(const DeltaParams& p, int i, const Vec3& x) {
  Arm arm;
  const double cp = std::cos(p.arm_angle[i]), sp = std::sin(p.arm_angle[i]);
  const double pu = cp * x.x() + sp * x.y() - p.base_u + p.effector_u;   // P_u + c
  const double pv = -sp * x.x() + cp * x.y() - p.base_v + p.effector_v;  // P_v + f
  const double pw = x.z();
  const double lean = p.shin * p.shin - pv * pv;  // (b sin theta3)^2
  if (!(lean > 0)) return arm;                    // the shin cannot reach P_v
  const double b_sin3 = std::sqrt(lean);
  const double reach = p.knee_joint + p.effector_joint + b_sin3;  // L
  const double rho = std::hypot(pu, pw);
  const double a = p.thigh;
  const double c = (rho * rho + a * a - reach * reach) / (2 * a * rho);
  if (!(rho > 0) || !(std::abs(c) <= 1)) return arm;  // thigh and shin cannot close
  arm.q = std::atan2(pw, pu) - std::acos(c);          // libnifalcon's knee (delta.h)
  arm.reachable = true;
  // G = (pu - a cos q)^2 + (pw - a sin q)^2 - L(pv)^2, dL/dpv = -pv / (b sin theta3).
  const double gu = 2 * (pu - a * std::cos(arm.q));
  const double gv = 2 * reach * pv / b_sin3;
  const double gw = 2 * (pw - a * std::sin(arm.q));
  arm.dg_dx << gu * cp - gv * sp, gu * sp + gv * cp, gw;  // through dP/dx = R(-phi)
  arm.dg_dq = 2 * a * (pu * std::sin(arm.q) - pw * std::cos(arm.q));
  return arm;
}

// Every arm at x; false when one cannot reach it.
bool solve_arms(const DeltaParams& p, const Vec3& x, Vec3& q, Mat3& dg_dx, Vec3& dg_dq) {
  for (int i = 0; i < 3; ++i) {
    const Arm arm = solve_arm(p, i, x);
    if (!arm.reachable) return false;
    q[i] = arm.q;
    dg_dx.row(i) = arm.dg_dx;
    dg_dq[i] = arm.dg_dq;
  }
  return true;
}

}  // namespace

JointSolution delta_inverse(const DeltaParams& p, const Vec3& x) noexcept {
  JointSolution s;
  s.n = 3;
  s.status = Status::kOutsideWorkspace;
  Vec3 q;
  Mat3 dg_dx;
  Vec3 dg_dq;
  if (!inside(p.workspace, x, 3) || !solve_arms(p, x, q, dg_dx, dg_dq)) return s;
  s.q = q;
  s.status = Status::kOk;
  return s;
}

namespace {

// Arm i's closure constraint at x for its given joint angle (cos, sin): G_i, its gradient in x
// and its derivative in q_i. No inverse trigonometry: what a Newton step of the forward
// kinematics needs, three square roots a step. False when the shin cannot reach P_v.
// Each arm's angle's cosine and sine, and each joint's: computed once a tick.
struct Angles {
  Vec3 arm_cos, arm_sin, q_cos, q_sin;
};

bool closure(const DeltaParams& p, const Angles& a, const Vec3& x, Vec3& g, Mat3& dg_dx,
             Vec3& dg_dq) {
  const Vec3 &cq = a.q_cos, &sq = a.q_sin;
  for (int i = 0; i < 3; ++i) {
    const double cp = a.arm_cos[i], sp = a.arm_sin[i];
    const double pu = cp * x.x() + sp * x.y() - p.base_u + p.effector_u;
    const double pv = -sp * x.x() + cp * x.y() - p.base_v + p.effector_v;
    const double pw = x.z();
    const double lean = p.shin * p.shin - pv * pv;
    if (!(lean > 0)) return false;
    const double b_sin3 = std::sqrt(lean);
    const double reach = p.knee_joint + p.effector_joint + b_sin3;
    const double du = pu - p.thigh * cq[i], dw = pw - p.thigh * sq[i];
    g[i] = du * du + dw * dw - reach * reach;
    const double gu = 2 * du, gv = 2 * reach * pv / b_sin3, gw = 2 * dw;
    dg_dx.row(i) << gu * cp - gv * sp, gu * sp + gv * cp, gw;
    dg_dq[i] = 2 * p.thigh * (pu * sq[i] - pw * cq[i]);
  }
  return true;
}

// Whether x is the point of q on libnifalcon's knee, not of the other one: Newton on G alone
// cannot tell the two apart (for the other knee G is zero too).
bool same_knee(const DeltaParams& p, const Vec3& q, const Vec3& x) {
  Vec3 at;
  Mat3 dg_dx;
  Vec3 dg_dq;
  if (!solve_arms(p, x, at, dg_dx, dg_dq)) return false;
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(std::remainder(q[i] - at[i], 2 * std::numbers::pi)) < 1e-6)) return false;
  }
  return true;
}

// Newton's iteration from pose.x (its status kNoConvergence on entry). Sets `wrong_knee` when
// it converged onto the point of q's other knee.
void iterate(const DeltaParams& p, const Angles& a, const Vec3& q, Pose& pose, bool& wrong_knee) {
  Vec3 g, dg_dq;
  Mat3 dg_dx, J;
  if (!closure(p, a, pose.x, g, dg_dx, dg_dq)) return;  // a shin cannot reach the start
  for (int step = 0;; ++step) {
    const bool ok = implicit_jacobian(dg_dx, dg_dq, 3, J);
    // G(x, q(x)) = 0, so G(x, q) = dG/dq (q - q(x)) to first order: the joint residual.
    const double residual = (g.array() / dg_dq.array()).abs().maxCoeff();
    if (ok && residual <= p.tolerance) {
      wrong_knee = !same_knee(p, q, pose.x);
      if (wrong_knee) return;
      pose.J = J;
      pose.status = judge(p.workspace, pose.x, 3, J, ok, p.near);
      return;
    }
    if (step >= p.max_iterations || !ok) return;
    // x(q) = x - (dG/dx)^-1 G to first order. A step that leaves the arms' reach (from far
    // away, near its edge) is halved until it does not, each try one of the budget.
    Vec3 dx = -dg_dx.partialPivLu().solve(g);
    while (!closure(p, a, pose.x + dx, g, dg_dx, dg_dq)) {
      if (++step >= p.max_iterations) return;
      dx /= 2;
    }
    pose.x += dx;
  }
}

}  // namespace

Pose delta_forward(const DeltaParams& p, const Vec3& q, const Vec3& guess) noexcept {
  Pose pose;
  pose.n = pose.m = 3;
  pose.status = Status::kNoConvergence;
  pose.x = guess.allFinite() ? guess : p.home;
  if (!q.allFinite()) return pose;
  Angles a;
  for (int i = 0; i < 3; ++i) {
    a.arm_cos[i] = std::cos(p.arm_angle[i]);
    a.arm_sin[i] = std::sin(p.arm_angle[i]);
  }
  a.q_cos = q.array().cos();
  a.q_sin = q.array().sin();
  bool wrong_knee = false;
  iterate(p, a, q, pose, wrong_knee);
  // The other knee's point solves G too, and would be a fixed point for every later tick that
  // starts from it: start once more from home, and leave home as the next tick's start.
  if (wrong_knee) {
    pose.x = p.home;
    iterate(p, a, q, pose, wrong_knee);
    if (pose.status == Status::kNoConvergence) pose.x = p.home;
  }
  return pose;
}

}  // namespace hapticd::kinematics
