// A driver paced by its in-process loopback peer: after configure, enable and every write it waits
// until the driver has sent what it was given (Device::wait_output: a driver with an output thread
// of its own) and the peer has handled it and answered, so the next read (the first tick's
// too) sees the answer whatever the two threads' timing (freerun, and real-time `--loopback` runs:
// peer_runner.h says why). The simulated device's clock is its protocol trigger, not the wall
// clock, so its samples are handed on without the wall-clock receive time (a host stall between the
// answer and the next tick is the loop's overrun, not an old sample). Everything else is the
// driver's own: its lifecycle, faults and descriptions.
#pragma once

#include <memory>

#include "drivers/device.h"
#include "sim/peers/peer_runner.h"

namespace hapticd::sim {

class PacedDevice final : public Device {
 public:
  PacedDevice(std::unique_ptr<Device> inner, const PeerRunner& runner)
      : inner_(std::move(inner)), runner_(runner) {}
  std::string_view driver_name() const noexcept override { return inner_->driver_name(); }
  void emergency_stop() noexcept override { inner_->emergency_stop(); }
  std::vector<std::string> notices() const override { return inner_->notices(); }
  std::span<const base::Counter> counters() const noexcept override { return inner_->counters(); }
  void wait_output() const noexcept override { inner_->wait_output(); }

 protected:
  DeviceInfo on_configure() override {
    inner_->configure();
    runner_.wait_idle();
    return inner_->info();
  }
  void on_enable() override {
    inner_->enable();
    runner_.wait_idle();
  }
  void on_disable() noexcept override { inner_->disable(); }
  void on_clear_fault() override { inner_->clear_fault(); }
  void on_close() noexcept override { inner_->close(); }
  IoStatus on_read(std::span<PositionSample> samples) noexcept override {
    const IoStatus r = inner_->read(samples, read_periods());  // the sim lives through them
    for (PositionSample& out : samples) {
      out.flags &= static_cast<std::uint8_t>(~kSampleHasTime);
      out.time_ns = 0;
    }
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) {
      set_fault_code(inner_->fault().code);
    }
    return r;
  }
  IoStatus on_write(std::span<const double> forces) noexcept override {
    const IoStatus r = inner_->write(forces);
    inner_->wait_output();
    runner_.wait_idle();
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) {
      set_fault_code(inner_->fault().code);
    }
    return r;
  }
  std::string describe(const DeviceFault&) const override { return inner_->describe_fault(); }

 private:
  std::unique_ptr<Device> inner_;
  const PeerRunner& runner_;
};

}  // namespace hapticd::sim
