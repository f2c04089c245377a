#include "kinematics/delta.h"

#include <Eigen/LU>
#include <cmath>

#include "kinematics/conditioning.h"

namespace hapticd::kinematics {
namespace {

// Each arm's angle's cosine and sine, and each joint's (forward kinematics only): computed
// once a call.
struct Angles {
  Vec3 arm_cos, arm_sin, q_cos, q_sin;
};

Angles arm_angles(const DeltaParams& p) {
  Angles a;
  for (int i = 0; i < 3; ++i) {
    a.arm_cos[i] = std::cos(p.arm_angle[i]);
    a.arm_sin[i] = std::sin(p.arm_angle[i]);
  }
  return a;
}

// Arm i's view of x (delta.h): (P_u + c, P_v + f, P_w) and the shin's reach L from the knee.
struct ArmPoint {
  double pu = 0.0, pv = 0.0, pw = 0.0;
  double b_sin3 = 0.0;  // b sin theta3
  double reach = 0.0;   // L
};

// False when the shin cannot reach P_v.
bool arm_point(const DeltaParams& p, const Angles& a, int i, const Vec3& x, ArmPoint& out) {
  const double cp = a.arm_cos[i], sp = a.arm_sin[i];
  out.pu = cp * x.x() + sp * x.y() - p.base_u + p.effector_u;
  out.pv = -sp * x.x() + cp * x.y() - p.base_v + p.effector_v;
  out.pw = x.z();
  const double lean = p.shin * p.shin - out.pv * out.pv;  // (b sin theta3)^2
  if (!(lean > 0)) return false;
  out.b_sin3 = std::sqrt(lean);
  out.reach = p.knee_joint + p.effector_joint + out.b_sin3;
  return true;
}

// Every arm's joint angle at x, libnifalcon's knee (delta.h); false when one cannot reach it.
bool solve_arms(const DeltaParams& p, const Angles& a, const Vec3& x, Vec3& q) {
  for (int i = 0; i < 3; ++i) {
    ArmPoint pt;
    if (!arm_point(p, a, i, x, pt)) return false;
    const double rho = std::hypot(pt.pu, pt.pw);
    const double c = (rho * rho + p.thigh * p.thigh - pt.reach * pt.reach) / (2 * p.thigh * rho);
    if (!(rho > 0) || !(std::abs(c) <= 1)) return false;  // thigh and shin cannot close
    q[i] = std::atan2(pt.pw, pt.pu) - std::acos(c);
  }
  return true;
}

// Every arm's closure constraint at x for its given joint angle: G_i = (pu - a cos q)^2 +
// (pw - a sin q)^2 - L(pv)^2, its gradient in x and its derivative in q_i. No inverse
// trigonometry: what a Newton step of the forward kinematics needs, three square roots a step.
bool closure(const DeltaParams& p, const Angles& a, const Vec3& x, Vec3& g, Mat3& dg_dx,
             Vec3& dg_dq) {
  for (int i = 0; i < 3; ++i) {
    ArmPoint pt;
    if (!arm_point(p, a, i, x, pt)) return false;
    const double du = pt.pu - p.thigh * a.q_cos[i], dw = pt.pw - p.thigh * a.q_sin[i];
    g[i] = du * du + dw * dw - pt.reach * pt.reach;
    // dL/dpv = -pv / (b sin theta3); dP/dx = R(-phi).
    const double gu = 2 * du, gv = 2 * pt.reach * pt.pv / pt.b_sin3, gw = 2 * dw;
    const double cp = a.arm_cos[i], sp = a.arm_sin[i];
    dg_dx.row(i) << gu * cp - gv * sp, gu * sp + gv * cp, gw;
    dg_dq[i] = 2 * p.thigh * (pt.pu * a.q_sin[i] - pt.pw * a.q_cos[i]);
  }
  return true;
}

// Whether x is the point of q on libnifalcon's knee, not of the other one: Newton on G alone
// cannot tell the two apart (for the other knee G is zero too).
bool same_knee(const DeltaParams& p, const Angles& a, const Vec3& q, const Vec3& x) {
  Vec3 at;
  if (!solve_arms(p, a, x, at)) return false;
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
      wrong_knee = !same_knee(p, a, q, pose.x);
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

JointSolution delta_inverse(const DeltaParams& p, const Vec3& x) noexcept {
  JointSolution s;
  s.n = 3;
  s.status = Status::kOutsideWorkspace;
  Vec3 q;
  if (!inside(p.workspace, x, 3) || !solve_arms(p, arm_angles(p), x, q)) return s;
  s.q = q;
  s.status = Status::kOk;
  return s;
}

Pose delta_forward(const DeltaParams& p, const Vec3& q, const Vec3& guess) noexcept {
  Pose pose;
  pose.n = pose.m = 3;
  pose.status = Status::kNoConvergence;
  pose.x = guess.allFinite() ? guess : p.home;
  if (!q.allFinite()) return pose;
  Angles a = arm_angles(p);
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
