// A Device whose every read/write outcome is scripted by the test, to drive the loop's fault
// paths deterministically. Records every force written. Configured and enabled on creation.
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
  IoStatus write_failure = IoStatus::kTransportFault;
  long read_sleep_ns = 0;  // makes every read this slow (overrun tests)
  std::uint32_t fault_code = 0;
  std::vector<double> writes;  // every force that reached the "transport"

  ScriptedDevice() {
    writes.reserve(1 << 16);
    configure();
    enable();
  }
  std::string_view driver_name() const noexcept override { return "scripted"; }

 protected:
  DeviceInfo on_configure() override { return {"scripted", 0, 0}; }
  void on_enable() override {}
  void on_disable() noexcept override {}
  void on_close() noexcept override {}
  IoStatus on_read(std::span<PositionSample> samples) noexcept override {
    PositionSample& out = samples.front();
    if (read_sleep_ns > 0) {
      const timespec ts{0, read_sleep_ns};
      nanosleep(&ts, nullptr);
    }
    const IoStatus r = script(reads_++, out);
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) set_fault_code(fault_code);
    return r;
  }
  IoStatus on_write(std::span<const double> forces) noexcept override {
    writes.push_back(forces.front());
    if (writes.size() - 1 != fail_write_at) return IoStatus::kOk;
    set_fault_code(fault_code);
    return write_failure;
  }
  std::string describe(const DeviceFault& f) const override {
    return "scripted failure, code " + std::to_string(f.code);
  }

 private:
  std::uint64_t reads_ = 0;
};

}  // namespace hapticd::testing
