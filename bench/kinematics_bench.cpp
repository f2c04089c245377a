// Cost of a device's kinematics per tick: forward kinematics with its Jacobian and the force
// mapped to joint torques (tau = J^T F), for today's one-axis device (joints, n = 1) and the
// Falcon's delta (3 joints, Newton from the previous tick's answer). The joint positions
// follow a circle through the workspace at about 0.3 m/s at 1 kHz, so each tick starts 0.3 mm
// from its answer, as on a device. And the same delta with a box of six walls in task space
// (control/scene.h): each wall's law along its normal, the sum through J^T and the joint
// saturation, on a circle that runs into four of the faces. Reports ns per tick and heap
// allocations per tick.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <vector>

#include "alloc_counter.h"
#include "control/scene.h"
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

// Each tick: the forward kinematics of the next point of the circle about the kind's centre
// (from the previous tick's answer), then `rest` on its pose; counts, per tick, the ticks
// `rest` returns true for (as `counted`) and the heap allocations.
template <class Rest>
void each_tick(benchmark::State& state, Kind kind, const char* counted, Rest rest) {
  hapticd::kinematics::Kinematics k;
  k.kind = kind;
  const Vec3 centre = kind == Kind::kDelta ? k.delta.home : Vec3::Zero();
  const auto q = circle(k, centre);
  Vec3 guess = centre;
  std::size_t i = 0;
  int n = 0;
  hapticd::testing::AllocationScope allocs;
  for (auto _ : state) {
    const hapticd::kinematics::Pose pose = forward(k, q[i++ % q.size()], guess);
    guess = pose.x;
    n += rest(pose) ? 1 : 0;
  }
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
  state.counters[counted] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kAvgIterations);
}

// The force mapped to joint torques; counts the poses that are not ok.
void fk_jacobian_torques(benchmark::State& state, Kind kind) {
  const Vec3 force(1.0, -2.0, 0.5);
  each_tick(state, kind, "not_ok", [&](const hapticd::kinematics::Pose& pose) {
    Vec3 tau = joint_torques(pose, force);
    benchmark::DoNotOptimize(tau);
    return pose.status != hapticd::kinematics::Status::kOk;
  });
}

void BM_Kinematics_Joints1(benchmark::State& state) { fk_jacobian_torques(state, Kind::kJoints); }
void BM_Kinematics_Delta(benchmark::State& state) { fk_jacobian_torques(state, Kind::kDelta); }

// A box of six walls, 2 cm from the delta's home each way (the 3 cm circle presses into the
// x and y faces), K 1000 N/m, B 1 N s/m.
hapticd::control::Scene delta_box() {
  std::vector<hapticd::control::WallGeometry> box;
  for (int a = 0; a < 3; ++a) {
    Vec3 n = Vec3::Zero();
    n[a] = 1.0;
    box.push_back({Vec3(0, 0, 0.11) + 0.02 * n, n});
    box.push_back({Vec3(0, 0, 0.11) - 0.02 * n, -n});
  }
  hapticd::config::Config c;
  c.wall.stiffness = 1000.0;
  c.wall.damping = 1.0;
  c.device.max_force = 5.0;
  const std::vector<hapticd::control::ControlLaw> laws(6, hapticd::control::make_control_law(c));
  return hapticd::control::Scene(box, laws);
}

// The box's walls on each pose, through J^T and the joint saturation; counts contact.
void BM_Scene_DeltaBox(benchmark::State& state) {
  hapticd::control::Scene scene = delta_box();
  const Vec3 limit = Vec3::Constant(2.0);
  each_tick(state, Kind::kDelta, "contact_fraction", [&](const hapticd::kinematics::Pose& pose) {
    const hapticd::control::SceneStep s = scene.step(pose, limit);
    benchmark::DoNotOptimize(s.tau);
    return (s.flags & hapticd::control::kControlContact) != 0;
  });
}

}  // namespace

BENCHMARK(BM_Kinematics_Joints1);
BENCHMARK(BM_Kinematics_Delta);
BENCHMARK(BM_Scene_DeltaBox);

BENCHMARK_MAIN();
