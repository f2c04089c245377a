// What the driver benchmarks share: an example configuration from config/, in freerun (the
// benchmark is the clock), with the benchmark's own overrides applied after; and the timed
// ticks through a driver and its peer; one of a driver's counters by name.
#pragma once

#include <benchmark/benchmark.h>

#include <array>
#include <chrono>
#include <fstream>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "base/joints.h"
#include "config/config_loader.h"
#include "sim/peers/loopback_peer.h"
#include "wiring/registry.h"

namespace hapticd::bench {

// The driver's counter `name` (Device::counters), 0 when it has none of that name.
inline std::uint64_t counter(const Device& device, std::string_view name) {
  for (const base::Counter& c : device.counters()) {
    if (c.name() == name) return c.value();
  }
  return 0;
}

inline config::Config load_example(const char* name, const std::vector<std::string>& sets = {}) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/config/" + name;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> o = {config::parse_override("loop.clock=freerun")};
  for (const std::string& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), path, o, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

// One tick per iteration: the device's read of every joint and a write of +-`force`
// (alternating) on each, then the peer answers in this thread. With `driver_only` the
// iteration's time is read and write alone (use ->UseManualTime()); otherwise it includes the
// peer's own work.
inline void run_ticks(benchmark::State& state, Device& device, sim::LoopbackPeer& peer,
                      bool driver_only, double force = 0.5) {
  std::array<PositionSample, base::kMaxJoints> s{};
  std::array<double, base::kMaxJoints> forces{};
  const std::size_t n = device.info().joints;
  forces.fill(force);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(device.read(std::span(s.data(), n)));
    benchmark::DoNotOptimize(device.write(std::span<const double>(forces.data(), n)));
    const auto t1 = std::chrono::steady_clock::now();
    peer.service();
    for (double& f : forces) f = -f;
    if (driver_only) state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
  }
}

}  // namespace hapticd::bench
