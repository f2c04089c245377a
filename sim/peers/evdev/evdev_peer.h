// The simulated evdev device on its end of the loopback socketpair (`hapticd run --loopback`,
// the conformance suite): the kernel's input device and its force-feedback driver in one, over
// the framing of drivers/evdev/evdev_wire.h, with the plant of device.sim behind it. It
// answers the driver's ioctls (the device's facts, EVIOCGRAB, EVIOCSFF, EVIOCRMFF), plays the
// one FF_CONSTANT effect as the EV_FF writes say, and steps the plant on each update of the
// effect - the protocol's trigger, once a tick - answering with the axis as an EV_ABS event
// and a SYN_REPORT. It stands for a device whose encoder is never still: it reports the axis
// after every step, changed or not, so only an injected silence is silent (the kernel's input
// core passes changes only; the kernel tests meet that). Its answers are held by the delay the
// driver declares, so a loopback run is the loop the gate analysed.
#pragma once

#include <array>
#include <atomic>
#include <vector>

#include "config/config.h"
#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_wire.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/loopback_peer.h"
#include "sim/sim_axis.h"

namespace hapticd::sim::evdev {

class SocketEvdevPeer final : public LoopbackPeer {
 public:
  // Not RT-safe. Throws std::invalid_argument for a plant that cannot be simulated.
  SocketEvdevPeer(const config::Config& cfg, io::UniqueFd fd, int link_delay_samples);

  void service() override;
  int fd() const noexcept override { return fd_.get(); }
  double applied_force() const noexcept override { return applied_.load(); }
  bool output_on() const noexcept override { return playing_.load(); }
  const Plant& plant() const noexcept override { return axis_.plant(); }
  // kStopAnswering: no more events; kDeviceFault: the device stops the effect and says so
  // (EV_FF_STATUS stopped); kTransportFault: the device vanishes. kSkipSequence: no (evdev
  // numbers nothing).
  bool inject(PeerFault fault) noexcept override;

  // The raw axis value the device reports for position `x`, and its range.
  std::int32_t raw_value(double x) const noexcept;
  drivers::evdev::AxisRange range() const noexcept { return range_; }

 private:
  void handle(const drivers::evdev::wire::Message& m);
  void answer(std::int32_t error, std::int32_t value = 0);
  void on_update(const drivers::evdev::wire::Effect& e);
  void apply() noexcept;
  void send_event(int type, int code, int value);
  void send(const drivers::evdev::wire::Message& m);
  void lose_host() noexcept;

  const drivers::evdev::EvdevSettings& settings_;
  io::UniqueFd fd_;
  SimAxis axis_;
  double counts_per_unit_;
  drivers::evdev::AxisRange range_;
  std::vector<double> fifo_;  // the last link delay + 1 positions, fifo_head_ the oldest
  std::size_t fifo_head_ = 0;
  drivers::evdev::wire::Effect effect_;
  bool uploaded_ = false;
  double gain_ = 1.0;
  std::atomic<bool> playing_{false};
  std::atomic<double> applied_{0.0};
  std::atomic<bool> silent_{false}, vanished_{false};
  enum : int { kNoFault, kFaultPending, kFaultSaid };
  std::atomic<int> fault_{kNoFault};  // an injected device fault: the effect stopped for good
  std::array<std::uint8_t, drivers::evdev::wire::kMaxMessage> rx_{};
  std::vector<std::uint8_t> tx_;
};

}  // namespace hapticd::sim::evdev
