// The GPIO driver's tick I/O cost with its loopback peer (BENCHMARKS.md, "GPIO driver"): one
// read (every pending edge batch, decoded) and one write (the PWM and direction state) through
// GpioDevice over the socketpair, the peer answering in the same thread between ticks, so the
// time is the driver's and the peer's own work and their system calls, with no thread
// hand-over in it. Also the decoder alone, and the sysfs PWM writer on a tmpfs file (a changed
// duty costs one write(2); an unchanged one none).
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "bench_support.h"
#include "config/config_loader.h"
#include "drivers/gpio/quadrature_decoder.h"
#include "drivers/gpio/sysfs_pwm.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;

// A tick: read, write a force, the peer steps the plant and answers. The plant is moved
// (imposed motion, 5 mm at 2 Hz: up to 6 counts a tick), so edges flow every tick.
void BM_GpioLoopbackTick(benchmark::State& state) {
  const config::Config cfg = bench::load_example(
      "gpio.yaml",
      {"device.sim.operator={kind: motion, offset: -0.02, amplitude: 0.005, frequency_hz: 2}"});
  wiring::Loopback pair = wiring::find_driver("gpio").make_loopback(cfg);
  Device& d = *pair.device;
  // configure() waits for the peer's answer to hello: answer it from this thread.
  std::thread helper([&] {
    for (int i = 0; i < 200 && d.state() == DeviceState::kUnconfigured; ++i) {
      pair.peer->service();
      usleep(1000);
    }
  });
  d.configure();
  helper.join();
  d.enable();
  pair.peer->service();
  PositionSample s;
  std::uint64_t ticks = 0;
  for (auto _ : state) {
    d.read(s);
    d.write(std::sin(static_cast<double>(ticks) * 0.01));
    pair.peer->service();  // the device's side: not the driver's cost, but in the loop
    ++ticks;
  }
  state.counters["ticks"] = static_cast<double>(ticks);
  d.close();
}
BENCHMARK(BM_GpioLoopbackTick);

void BM_DecoderEdge(benchmark::State& state) {
  drivers::gpio::QuadratureDecoder dec({});
  dec.reset(0);
  std::int64_t t = 0;
  std::int64_t count = 0;
  for (auto _ : state) {
    const std::uint8_t from = drivers::gpio::state_of_count(count);
    const std::uint8_t to = drivers::gpio::state_of_count(count + 1);
    const std::uint8_t diff = from ^ to;
    dec.apply({t += 1000, 0,
               (diff & drivers::gpio::kBitA) ? drivers::gpio::Line::kA : drivers::gpio::Line::kB,
               (to & diff) != 0});
    ++count;
  }
  benchmark::DoNotOptimize(dec.count());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DecoderEdge);

// The PWM writer on regular files (tmpfs): the cost of a changed duty (one write(2)) and of an
// unchanged one (none).
void BM_SysfsPwmWrite(benchmark::State& state) {
  namespace fs = std::filesystem;
  const fs::path root =
      fs::temp_directory_path() / ("hapticd-pwm-bench-" + std::to_string(getpid()));
  fs::create_directories(root / "pwmchip0" / "pwm0");
  for (const char* f : {"export"}) std::ofstream(root / "pwmchip0" / f);
  for (const char* f : {"period", "duty_cycle", "enable", "polarity"}) {
    std::ofstream(root / "pwmchip0" / "pwm0" / f) << (f[1] == 'o' ? "normal\n" : "0\n");
  }
  drivers::gpio::SysfsPwm pwm;
  pwm.open({root.string(), 0, 0, 50'000, false});
  const bool changing = state.range(0) != 0;
  std::uint64_t duty = 0;
  for (auto _ : state) {
    if (changing) duty = (duty + 1) % 50'000;
    pwm.write(duty);
  }
  state.counters["writes_per_tick"] =
      static_cast<double>(pwm.writes()) / static_cast<double>(state.iterations());
  pwm.close();
  fs::remove_all(root);
}
BENCHMARK(BM_SysfsPwmWrite)->Arg(1)->Arg(0)->ArgName("duty_changes");

}  // namespace

BENCHMARK_MAIN();
