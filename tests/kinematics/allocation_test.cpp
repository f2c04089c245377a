// Nothing on the per-tick path allocates: forward and inverse of every kind, J^T F, x' = J q'
// and the saturation, counted by the project's allocation counter (tests/support).
#include <gtest/gtest.h>

#include <cmath>

#include "alloc_counter.h"
#include "check.h"
#include "kinematics/kinematics.h"
#include "kinematics/saturation.h"

namespace hapticd::kinematics {
namespace {

Kinematics of(Kind kind) {
  Kinematics k;
  k.kind = kind;
  k.joints.n = 1;
  return k;
}

TEST(Allocation, PerTickFunctionsAllocateNothing) {
  // A tick's worth of inputs: a task position inside every kind's box, moved a little each tick.
  for (Kind kind : {Kind::kJoints, Kind::kCartesian, Kind::kPantograph, Kind::kDelta}) {
    const Kinematics k = of(kind);
    const Vec3 centre = kind == Kind::kDelta        ? Vec3(0.0, 0.0, 0.11)
                        : kind == Kind::kPantograph ? Vec3(0.0, 0.13, 0.0)
                                                    : Vec3(0.01, 0.02, 0.03);
    Vec3 guess = centre;
    double checksum = 0.0;
    int solved = 0;
    hapticd::testing::AllocationScope scope;
    for (int tick = 0; tick < 2000; ++tick) {
      const Vec3 x = centre + 0.02 * Vec3(std::sin(tick * 0.01), std::cos(tick * 0.013), 0.0);
      const JointSolution s = inverse(k, x);
      const Pose pose = forward(k, s.q, guess);
      guess = pose.x;
      const Vec3 tau = joint_torques(pose, Vec3(1.0, -2.0, 0.5));
      const Saturated sat = saturate(tau, Vec3::Constant(0.05), pose.n);
      checksum += sat.tau.sum() + task_velocity(pose, s.q).sum() +
                  static_cast<double>(pose.status == Status::kOk);
      solved += pose.status == Status::kOk ? 1 : 0;
    }
    EXPECT_EQ(scope.count(), 0u) << kind_name(kind);
    EXPECT_EQ(solved, 2000) << kind_name(kind) << ": ticks that returned early prove nothing";
    EXPECT_TRUE(std::isfinite(checksum));
  }
  if (!hapticd::testing::malloc_is_counted()) {
    GTEST_LOG_(INFO) << "malloc is not interposed here (sanitizers): operator new only";
  }
}

}  // namespace
}  // namespace hapticd::kinematics
