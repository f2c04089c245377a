// A Device whose every read/write outcome is scripted by the test, to drive the loop's fault
// paths deterministically. Records every force written.
#pragma once

#include <time.h>

#include <cmath>
#include <functional>
#include <vector>

#include "drivers/device.h"

namespace hapticd::testing {

class ScriptedDevice final : public Device {
 public:
  // script(tick, sample) -> status; the default reads 1 mm inside a wall at 0.
  std::function<IoStatus(std::uint64_t, PositionSample&)> script = [](std::uint64_t,
                                                                      PositionSample& s) {
    s.position = 0.001;
    return IoStatus::kOk;
  };
  std::uint64_t fail_write_at = UINT64_MAX;
  long read_sleep_ns = 0;  // makes every read this slow (overrun tests)
  std::vector<double> writes;

  ScriptedDevice() { writes.reserve(1 << 16); }
  void configure() override {}
  void enable_output() override {}
  void disable_output() noexcept override {}
  IoStatus read(PositionSample& out) noexcept override {
    if (read_sleep_ns > 0) {
      const timespec ts{0, read_sleep_ns};
      nanosleep(&ts, nullptr);
    }
    return script(reads_++, out);
  }
  IoStatus write(double force) noexcept override {
    writes.push_back(force);
    return writes.size() - 1 == fail_write_at ? IoStatus::kError : IoStatus::kOk;
  }
  int transport_delay_samples() const noexcept override { return 0; }
  std::string_view name() const noexcept override { return "scripted"; }
  std::string describe_error() const override { return "scripted failure"; }
  double last_command() const noexcept override { return writes.empty() ? 0.0 : writes.back(); }
  bool output_enabled() const noexcept override { return false; }

 private:
  std::uint64_t reads_ = 0;
};

}  // namespace hapticd::testing
