// The whole tick of a device of three joints (docs/kinematics.md, the loop at several joints):
// the servo loop in freerun over a device that hands back a precomputed delta motion (so no
// plant is timed), through config/sim-delta.yaml's scene: the samples checked per joint, the
// delta's forward kinematics, six walls each with its passivity observer, J^T and the
// saturation, three torques written, the record pushed, timed by bench/full_tick.h.
#include <benchmark/benchmark.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include "config/config_loader.h"
#include "control/scene.h"
#include "full_tick.h"
#include "loop/servo_loop.h"
#include "telemetry/state_block.h"

namespace {

using hapticd::kinematics::Vec3;

// config/sim-delta.yaml; with `attractor`, an attractor at the box's centre beside its walls.
hapticd::config::Config delta_config(bool attractor = false) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/sim-delta.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  if (attractor) {
    yaml.insert(yaml.find("\nsafety:"),
                "\n  - {kind: attractor, point: [0, 0, 0.11], "
                "stiffness: 200, damping: 0.05}");
  }
  return hapticd::config::load_config_text(yaml, "sim-delta.yaml");
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

// What one run drives: the path, the scene of config/sim-delta.yaml's six walls with their
// observers, and the loop over them; with `clients`, what a daemon with a control socket adds
// each tick (the state block published, the moves and a client's force looked at).
struct DeltaRig {
  DeltaRig(const hapticd::config::Config& cfg, hapticd::bench::TickRing& ring,
           hapticd::loop::LoopOptions o, bool clients)
      : block(4096, cfg.loop.period_ns(), 3, 3),
        force({2.0, 100000000, 50000000, 1.0, cfg.loop.sample_period_s()}),
        device(cfg.device.kinematics),
        unused(hapticd::control::make_control_law(cfg)),
        walls(scene_walls(cfg)),
        state(cfg.device.kinematics, walls, cfg.device.max_force.per_joint()),
        loop(device, unused, &ring, with_scene(o, &state, clients ? this : nullptr)) {}
  // cfg's scene with an observer on each channel (a wall's normal, an attractor's axes).
  static hapticd::loop::SceneWalls scene_walls(const hapticd::config::Config& cfg) {
    auto scene = std::make_unique<hapticd::control::Scene>(hapticd::control::make_scene(cfg));
    const std::size_t channels = scene->channels();
    return hapticd::loop::SceneWalls(std::move(scene),
                                     std::vector<hapticd::control::ObserverParams>(
                                         channels, hapticd::control::observer_params(cfg, 0)));
  }
  static hapticd::loop::LoopOptions with_scene(hapticd::loop::LoopOptions o,
                                               hapticd::loop::SceneState* s, DeltaRig* clients) {
    o.scene = s;
    if (clients != nullptr) {
      o.state = &clients->block;
      o.wall_moves = &clients->moves;
      o.client_force = &clients->force;
    }
    return o;
  }
  hapticd::telemetry::StateBlock block;
  hapticd::loop::WallMoves moves;
  hapticd::loop::ClientForce force;
  PathDevice device;
  hapticd::control::Controller unused;
  hapticd::loop::SceneWalls walls;
  hapticd::loop::SceneState state;
  hapticd::loop::ServoLoop loop;
};

void BM_FullTick_Delta(benchmark::State& state) {
  const hapticd::config::Config cfg = delta_config(state.range(2) != 0);
  hapticd::bench::run_full_ticks(
      state, static_cast<std::uint64_t>(state.range(0)), {},
      [&](hapticd::bench::TickRing& ring, const hapticd::loop::LoopOptions& o) {
        return std::make_unique<DeltaRig>(cfg, ring, o, state.range(1) != 0);
      });
}

BENCHMARK(BM_FullTick_Delta)
    ->Args({100000, 0, 0})
    ->Args({100000, 1, 0})
    ->Args({100000, 0, 1})
    ->ArgNames({"ticks", "clients", "attractor"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
