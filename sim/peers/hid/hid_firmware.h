// The simulated HID device's firmware: the plant (a SimAxis; for a mechanism of several joints,
// the Mechanism of device.kinematics, one motor per joint) behind a USB HID interface that
// speaks either profile of the HID driver, with the driver's own pure codecs
// (drivers/hid/report_layout.h, pid_protocol.h). Like firmware it steps the plant when the
// force command arrives (the output report; for PID, Set Constant Force) and answers with an
// input report; it answers the enable with its state at rest, without a step. The transport is
// not its business: SocketHidPeer carries it over the loopback socketpair, HidgPeer over a USB
// HID gadget's /dev/hidgN, UhidPeer over /dev/uhid, RawGadgetPeer as a USB device of its own.
//
// A loopback peer also stands in for the USB link's latency: with link_delay_samples d it
// answers with the position measured d steps earlier, so a loopback run is the loop the gate
// analysed with the driver's declared delay (and follows a sim run with wall.delay_samples d).
// On a real USB gadget the link itself is the delay and d is 0.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "config/config.h"
#include "drivers/hid/hid_settings.h"
#include "sim/mechanism.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_state.h"
#include "sim/sim_axis.h"

namespace hapticd::sim::hid {

class HidFirmware {
 public:
  // How many sequence numbers an injected kSkipSequence skips.
  static constexpr std::uint32_t kSkippedReports = 50;

  // Sends one input report to the host (report id first when numbered).
  using Send = std::function<void(std::span<const std::uint8_t>)>;

  virtual ~HidFirmware() = default;

  // What the device declares itself to be.
  virtual const std::vector<std::uint8_t>& descriptor() const = 0;
  // Peer thread. An output report from the host (id first).
  virtual void on_output(std::span<const std::uint8_t> report, const Send& send) = 0;
  // Peer thread. A feature report set by the host; 0 or the errno the host sees (EPIPE: a
  // stall, for a report the device does not have).
  virtual int on_set_feature(std::span<const std::uint8_t> report, const Send& send) = 0;
  // Peer thread. Feature report `id` as the device answers it (id first), or an errno.
  virtual int on_get_feature(std::uint8_t id, std::vector<std::uint8_t>& out) = 0;
  // Peer thread. How long the firmware keeps a force without hearing from the host (its
  // watchdog), in ms; 0: forever.
  virtual double watchdog_ms() const noexcept = 0;

  // Peer thread. The host is gone (transport lost, watchdog expired): zero force, output off.
  void lose_host() noexcept;
  // Any thread: what the person feels at once when the device vanishes (the peer thread
  // calls lose_host() when it next runs).
  void vanish() noexcept { felt_.vanish(); }
  // Any thread: what the person feels (zero and off at once after vanish()).
  double applied_force() const noexcept { return felt_.force(); }
  bool output_on() const noexcept { return felt_.on(); }
  const Plant& plant() const noexcept { return axis_.plant(); }
  // The mechanism of several joints, or null for one joint (plant() is it).
  const JointPlant* joint_plant() const noexcept {
    return mechanism_ ? &mechanism_->plant() : nullptr;
  }
  // Any thread. kTransportFault is the transport's to produce (returns false here).
  virtual bool inject(PeerFault fault) noexcept;
  // Peer thread, for peers on a real link (HidgPeer, UhidPeer): the host was heard at `now`;
  // and the firmware's watchdog, which drops the output when the host has been silent longer
  // than watchdog_ms() while it was on. True when it tripped just now.
  void heard_host(std::chrono::steady_clock::time_point now) noexcept { last_heard_ = now; }
  bool check_watchdog(std::chrono::steady_clock::time_point now) noexcept;
  std::uint64_t watchdog_trips() const noexcept { return trips_.load(); }
  // Input reports not sent because the host was not taking them (HidgPeer counts).
  std::uint64_t answers_dropped() const noexcept { return dropped_.load(); }
  void count_dropped() noexcept { dropped_.fetch_add(1); }

 protected:
  HidFirmware(const config::Config& cfg, int link_delay_samples);
  // The amplifier; switching drops the held force to zero.
  void set_output(bool on) noexcept;
  // Peer thread: whether the firmware has its amplifier on, what its reports say. Not
  // output_on(): a vanish() from another thread zeroes what is felt at once, and a state report
  // built before this thread sees the link gone must not say the amplifier went off by itself
  // (the host would read a device fault where the wire was cut).
  bool amplifier_on() const noexcept {
    return mechanism_ ? mechanism_->output_on(0) : axis_.output_on();
  }
  // The joints the device drives (device.kinematics).
  std::size_t joints() const noexcept {
    return mechanism_ ? static_cast<std::size_t>(mechanism_->joints()) : 1;
  }
  // Holds `force` (zero while off) and advances the plant one period.
  void step(double force) noexcept { step(std::span<const double>(&force, 1)); }
  // The same for every joint: joint i's force is entry i (joints() of them).
  void step(std::span<const double> forces) noexcept;
  // Holds `force` from now on without a step: what plays changed between two commands.
  void hold(std::span<const double> forces) noexcept;
  // The position the device reports: measured link_delay steps ago (joint j's).
  double measured_position(std::size_t j = 0) const noexcept { return fifo_[fifo_head_][j]; }
  double velocity() const noexcept { return axis_.plant().velocity(); }
  // Sequence number of the next answer (skips when injected).
  std::uint32_t next_sequence() noexcept;
  bool answering() const noexcept { return !faults_.active(PeerFault::kStopAnswering); }
  bool device_fault() const noexcept { return faults_.active(PeerFault::kDeviceFault); }

 private:
  // Publishes what the person feels: the largest torque a motor holds.
  void publish() noexcept;
  // Every joint's encoder now.
  std::array<double, base::kMaxJoints> encoders() noexcept;

  SimAxis axis_;
  std::unique_ptr<Mechanism> mechanism_;  // several joints; axis_ unused then
  // The last link_delay + 1 positions of every joint; fifo_head_ the oldest.
  std::vector<std::array<double, base::kMaxJoints>> fifo_;
  std::size_t fifo_head_ = 0;
  std::uint32_t sequence_ = 0;
  FeltOutput felt_;
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kSkipSequence,
                                PeerFault::kDeviceFault};
  std::atomic<std::uint64_t> dropped_{0};
  std::chrono::steady_clock::time_point last_heard_ = std::chrono::steady_clock::now();
  std::atomic<std::uint64_t> trips_{0};
};

// A peer that carries a HidFirmware over one transport (socketpair, gadget, uhid, raw gadget):
// what the person feels is the firmware's. Subclasses move bytes; the firmware decides.
class FirmwarePeer : public LoopbackPeer {
 public:
  double applied_force() const noexcept final { return fw_->applied_force(); }
  bool output_on() const noexcept final { return fw_->output_on(); }
  const Plant& plant() const noexcept final { return fw_->plant(); }
  const JointPlant* joint_plant() const noexcept final { return fw_->joint_plant(); }

 protected:
  explicit FirmwarePeer(std::unique_ptr<HidFirmware> firmware) : fw_(std::move(firmware)) {}
  std::unique_ptr<HidFirmware> fw_;
};

// Not RT-safe. The firmware for `cfg`'s device.hid profile. Throws config::ConfigError for a
// plant that cannot be simulated.
std::unique_ptr<HidFirmware> make_firmware(const config::Config& cfg, int link_delay_samples);

}  // namespace hapticd::sim::hid
