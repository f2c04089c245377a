// The whole tick of a device of three joints (docs/kinematics.md, the loop at several joints):
// the servo loop in freerun over a device that hands back a precomputed delta motion (so no
// plant is timed), through config/sim-delta.yaml's scene: the samples checked per joint, the
// delta's forward kinematics, six walls each with its passivity observer, J^T and the
// saturation, three torques written, the record pushed. Reports ns per tick, the loop's own
// compute-time percentiles and heap allocations per tick.
#include <benchmark/benchmark.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/scene.h"
#include "loop/servo_loop.h"

namespace {

using hapticd::kinematics::Vec3;

hapticd::config::Config delta_config() {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/sim-delta.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return hapticd::config::load_config_text(text.str(), "sim-delta.yaml");
}

// Joint positions of a circle through the +x, +y and -z faces of the box (three walls in
// contact a quarter of the time), 1024 ticks a turn, solved before anything is timed.
class PathDevice final : public hapticd::Device {
 public:
  explicit PathDevice(const hapticd::kinematics::Kinematics& k) {
    for (int i = 0; i < 1024; ++i) {
      const double a = 2.0 * M_PI * i / 1024.0;
      const Vec3 x(0.012 + 0.012 * std::cos(a), 0.012 + 0.012 * std::sin(a),
                   0.095 - 0.012 * std::sin(a));
      path_.push_back(hapticd::kinematics::inverse(k, x).q);
    }
    configure();
    enable();
  }
  std::string_view driver_name() const noexcept override { return "path"; }

 protected:
  hapticd::DeviceInfo on_configure() override { return {"path", 0, 0, 3}; }
  void on_enable() override {}
  void on_disable() noexcept override {}
  void on_close() noexcept override {}
  hapticd::IoStatus on_read(std::span<hapticd::PositionSample> samples) noexcept override {
    const Vec3& q = path_[next_++ & 1023];
    for (std::size_t j = 0; j < samples.size(); ++j) samples[j].position = q[static_cast<int>(j)];
    return hapticd::IoStatus::kOk;
  }
  hapticd::IoStatus on_write(std::span<const double>) noexcept override {
    return hapticd::IoStatus::kOk;
  }
  std::string describe(const hapticd::DeviceFault&) const override { return "path"; }

 private:
  std::vector<Vec3> path_;
  std::size_t next_ = 0;
};

void BM_FullTick_Delta(benchmark::State& state) {
  const hapticd::config::Config cfg = delta_config();
  const auto ticks = static_cast<std::uint64_t>(state.range(0));
  hapticd::telemetry::SpscRing<hapticd::telemetry::TickRecord> ring(ticks + 1);
  std::vector<hapticd::telemetry::TickRecord> drained(ticks + 1);
  std::uint64_t allocations = 0, total = 0;
  std::int64_t p50 = 0, p99 = 0, max = 0;
  for (auto _ : state) {
    state.PauseTiming();
    PathDevice device(cfg.device.kinematics);
    hapticd::control::Controller unused(hapticd::control::make_control_law(cfg));
    hapticd::control::Scene scene = hapticd::control::make_scene(cfg);
    hapticd::loop::SceneState st(cfg.device.kinematics, scene, Vec3::Constant(cfg.device.max_force),
                                 std::vector<hapticd::control::ObserverParams>(
                                     cfg.walls.size(), hapticd::control::observer_params(cfg, 0)));
    hapticd::loop::LoopOptions lo;
    lo.sample.realtime = false;
    lo.max_ticks = ticks;
    lo.scene = &st;
    hapticd::loop::ServoLoop loop(device, unused, &ring, lo);
    const std::atomic<bool> stop{false};
    state.ResumeTiming();
    hapticd::testing::AllocationScope allocs;
    const auto r = loop.run(stop);
    allocations += allocs.count();
    state.PauseTiming();
    total += r.ticks;
    ring.pop_many(drained.data(), drained.size());
    const auto& h = loop.compute_time();
    p50 = std::max(p50, h.percentile_ns(0.5));
    p99 = std::max(p99, h.percentile_ns(0.99));
    max = std::max(max, h.max_ns());
    state.ResumeTiming();
  }
  state.counters["ns_per_tick"] = benchmark::Counter(
      static_cast<double>(total), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["allocs_per_tick"] =
      static_cast<double>(allocations) / static_cast<double>(std::max<std::uint64_t>(total, 1));
  state.counters["compute_p50_ns"] = static_cast<double>(p50);
  state.counters["compute_p99_ns"] = static_cast<double>(p99);
  state.counters["compute_max_ns"] = static_cast<double>(max);
}

BENCHMARK(BM_FullTick_Delta)->Arg(100000)->ArgName("ticks")->Unit(benchmark::kMillisecond);

}  // namespace
