// The CAN driver's Device (docs/drivers/can.md): the lifecycle over a CanLink (a SocketCAN
// interface, or the loopback socketpair) and a CanProfile (cia402 or odrive) driving the nodes
// of device.can, one joint each: a fault of any node is the device's. Each tick it
// drains everything the socket queued (bus events decoded, malformed messages counted) and
// hands each frame to the profile; it sends the profile's frames without ever blocking (a
// full TX queue is counted, and faults only after tx_full_fault_ticks ticks in a row), and
// watches every drive's heartbeat in ticks. The first fault a tick meets is the one latched, and
// its sentence names what else the bus showed. Counters are Device::counters (can_link.h).
#pragma once

#include <array>
#include <memory>

#include "base/joints.h"
#include "drivers/can/can_link.h"
#include "drivers/can/can_profile.h"
#include "drivers/can/can_settings.h"
#include "drivers/device.h"

namespace hapticd::drivers::can {

class CanDevice final : public Device {
 public:
  // Not RT-safe. `open` opens the transport at each configure. keeper_priority: see
  // make_cia402_profile (CiA 402 only).
  CanDevice(const CanSettings& settings, double sample_period_s, CanLink::Opener open,
            int keeper_priority = 0);
  ~CanDevice() override;

  std::string_view driver_name() const noexcept override { return "can"; }
  // Async-signal-safe: write(2) of the profile's prebuilt zero-torque and disable frames.
  void emergency_stop() noexcept override { link_.emergency_stop(); }
  std::vector<std::string> notices() const override { return profile_->notices(); }
  std::span<const base::Counter> counters() const noexcept override { return link_.counters(); }

 protected:
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_clear_fault() override;
  void on_close() noexcept override;
  // RT-safe: called every tick.
  IoStatus on_read(std::span<PositionSample> samples) noexcept override;
  // RT-safe: called every tick.
  IoStatus on_write(std::span<const double> forces) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  // RT-safe: called every tick. Every frame waiting (a bound per tick: a babbling bus cannot
  // hold the RT thread), each to the profile; `fresh` says whether one was a sample.
  IoStatus drain(bool active, unsigned& fresh) noexcept;
  // RT-safe: called every tick. A full queue is judged at the end of the tick; false when the
  // device must fault (recorded).
  bool send(const CanFrame& f) noexcept;
  bool end_tick_tx() noexcept;
  // RT-safe. Records the first fault of this tick; the status the hook returns.
  IoStatus raise(CanFault fault) noexcept;
  void clear_pending() noexcept;

  const int tx_full_fault_ticks_;
  const std::size_t joints_;  // one per node
  CanLink link_;
  std::unique_ptr<CanProfile> profile_;
  const std::uint32_t heartbeat_limit_ticks_;  // heartbeat_timeout_ms in ticks
  std::array<std::uint32_t, base::kMaxJoints> ticks_since_heartbeat_{};  // per node
  int tx_full_streak_ = 0;
  bool tx_full_this_tick_ = false;
  IoStatus pending_status_ = IoStatus::kOk;
  CanFault pending_;  // the first fault since configure, enable or clear_fault
};

}  // namespace hapticd::drivers::can
