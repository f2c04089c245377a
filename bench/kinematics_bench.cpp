// Cost of a device's kinematics per tick: forward kinematics with its Jacobian and the force
// mapped to joint torques (tau = J^T F), for today's one-axis device (joints, n = 1) and the
// Falcon's delta (3 joints, Newton from the previous tick's answer). The joint positions
// follow a circle through the workspace at about 0.3 m/s at 1 kHz, so each tick starts 0.3 mm
// from its answer, as on a device. Reports ns per tick and heap allocations per tick.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>

#include "alloc_counter.h"
#include "kinematics/kinematics.h"

namespace {

using hapticd::kinematics::Kind;
using hapticd::kinematics::Vec3;

// Joint positions along a 3 cm circle about the kind's centre, one per tick.
std::array<Vec3, 628> circle(const hapticd::kinematics::Kinematics& k, const Vec3& centre) {
  std::array<Vec3, 628> q{};
  for (std::size_t i = 0; i < q.size(); ++i) {
    const double a = 0.01 * static_cast<double>(i);
    q[i] = inverse(k, centre + Vec3(0.03 * std::cos(a), 0.03 * std::sin(a), 0.0)).q;
  }
  return q;
}

void fk_jacobian_torques(benchmark::State& state, Kind kind) {
  hapticd::kinematics::Kinematics k;
  k.kind = kind;
  const Vec3 centre = kind == Kind::kDelta ? k.delta.home : Vec3::Zero();
  const auto q = circle(k, centre);
  const Vec3 force(1.0, -2.0, 0.5);
  Vec3 guess = centre;
  std::size_t i = 0;
  int not_ok = 0;
  hapticd::testing::AllocationScope allocs;
  for (auto _ : state) {
    const hapticd::kinematics::Pose pose = forward(k, q[i++ % q.size()], guess);
    guess = pose.x;
    not_ok += pose.status != hapticd::kinematics::Status::kOk;
    Vec3 tau = joint_torques(pose, force);
    benchmark::DoNotOptimize(tau);
  }
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
  state.counters["not_ok"] = not_ok;
}

void BM_Kinematics_Joints1(benchmark::State& state) { fk_jacobian_torques(state, Kind::kJoints); }
void BM_Kinematics_Delta(benchmark::State& state) { fk_jacobian_torques(state, Kind::kDelta); }

}  // namespace

BENCHMARK(BM_Kinematics_Joints1);
BENCHMARK(BM_Kinematics_Delta);

BENCHMARK_MAIN();
