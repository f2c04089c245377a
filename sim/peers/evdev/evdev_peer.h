// The simulated evdev device on its end of the loopback socketpair (`hapticd run --loopback`,
// the conformance suite): the kernel's input device and its force-feedback driver in one, over
// the framing of drivers/evdev/evdev_wire.h, with the plant of device.sim behind it (two axes:
// the mechanism of device.kinematics, sim/mechanism.h, as a joystick's two gimbal axes). It
// answers the driver's ioctls (the device's facts, EVIOCGRAB, EVIOCSFF, EVIOCRMFF), plays the
// FF_CONSTANT effects as the EV_FF writes say, renders each as <linux/input.h> encodes its
// direction (an axis whose direction_deg is 90 or 270 is the effect's x, 0 or 180 its y:
// plane_force), and steps the plant on each update of the tick's last effect - the protocol's
// trigger, once a tick - answering with each axis as an EV_ABS event and one SYN_REPORT. It stands
// for a device whose encoder is never still: it reports the axis after every step, changed or not,
// so only an injected silence is silent (the kernel's input core passes changes only; the kernel
// tests meet that). Its answers are held by the delay the driver declares, so a loopback run is the
// loop the gate analysed. Each update is answered on the descriptor the driver handed over
// (kAnswers), as EVIOCSFF returns; told to, it takes an update only after a while, as a device in
// user space slow to answer UI_FF_UPLOAD does (its own slowness is then its delay: it holds nothing
// more). An EV_FF write (a stop) that comes meanwhile acts once that update is taken, as the
// kernel's evdev lets a write to the node through only then (it holds the node's mutex across
// EVIOCSFF).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "config/config.h"
#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_wire.h"
#include "drivers/io/unique_fd.h"
#include "sim/mechanism.h"
#include "sim/peers/loopback_peer.h"
#include "sim/sim_axis.h"

namespace hapticd::sim::evdev {

class SocketEvdevPeer final : public LoopbackPeer {
 public:
  // Not RT-safe. Throws std::invalid_argument for a plant that cannot be simulated.
  SocketEvdevPeer(const config::Config& cfg, io::UniqueFd fd, int link_delay_samples);

  void service() override;
  int fd() const noexcept override { return fd_.get(); }
  // While an update waits to be taken: the ms until it is.
  int service_interval_ms() const noexcept override;
  // The largest force on a joint (two axes: the one larger in size).
  double applied_force() const noexcept override { return applied_.load(); }
  bool output_on() const noexcept override { return playing_.load(); }
  // One axis: its plant; two: joint_plant() is the mechanism, plant() an unused axis of its own.
  const Plant& plant() const noexcept override { return axis_.plant(); }
  const JointPlant* joint_plant() const noexcept override {
    return mechanism_ ? &mechanism_->plant() : nullptr;
  }
  // Any thread. The force on joint j now (N).
  double joint_force(int j) const noexcept { return joint_force_[static_cast<std::size_t>(j)]; }
  // kStopAnswering: no more events; kDeviceFault: the device stops the effect and says so
  // (EV_FF_STATUS stopped); kTransportFault: the device vanishes. kSkipSequence: no (evdev
  // numbers nothing).
  bool inject(PeerFault fault) noexcept override;
  // Any thread. Each update received from now on is taken (applied, the plant stepped, the
  // axis reported and the update answered) `latency` after it came; zero: at once.
  void take_updates_after(std::chrono::nanoseconds latency) noexcept {
    latency_ns_.store(latency.count());
  }
  // Any thread. Updates taken so far, and the level of the last one.
  std::uint64_t updates_taken() const noexcept { return updates_taken_.load(); }
  int last_level() const noexcept { return last_level_.load(); }

  // The raw value axis j reports for position `x`, and its range.
  std::int32_t raw_value(int j, double x) const noexcept;
  drivers::evdev::AxisRange range(int j = 0) const noexcept { return range_[j]; }

 private:
  // An update to take at its time, or an EV_FF write that came behind one (due_ns 0).
  struct Pending {
    std::int64_t due_ns;
    drivers::evdev::wire::Message m;
  };
  void receive(std::size_t n, int passed_fd);
  void handle(const drivers::evdev::wire::Message& m);
  void answer(std::int32_t error, std::int32_t value = 0);
  void answer_update(std::int32_t error, std::int32_t value);
  void on_update(const drivers::evdev::wire::Effect& e);
  void write_ff(int code, int value);
  void take_update(const drivers::evdev::wire::Effect& e);
  void step_and_report();
  void take_due();
  void apply() noexcept;
  int effect_index(int id) const noexcept;
  void upload(const drivers::evdev::wire::Message& m);
  void query(const drivers::evdev::wire::Message& m);
  void send_event(int type, int code, int value);
  void send(const drivers::evdev::wire::Message& m);
  void lose_host() noexcept;

  static constexpr int kAxes = 2;
  const drivers::evdev::EvdevSettings& settings_;
  int joints_;
  int effects_held_;  // 1, or 2 with effect: per_axis
  io::UniqueFd fd_;
  io::UniqueFd answers_;  // where updates are answered (kAnswers)
  SimAxis axis_;
  std::unique_ptr<Mechanism> mechanism_;  // two axes
  double counts_per_unit_;
  std::array<drivers::evdev::AxisRange, kAxes> range_{};
  // The last link delay + 1 positions of each axis, fifo_head_ the oldest.
  std::vector<std::array<double, kAxes>> fifo_;
  std::size_t fifo_head_ = 0;
  std::array<drivers::evdev::wire::Effect, kAxes> effects_{};
  std::array<bool, kAxes> uploaded_{}, effect_playing_{};
  double gain_ = 1.0;
  std::atomic<bool> playing_{false};
  std::atomic<double> applied_{0.0};
  std::array<std::atomic<double>, kAxes> joint_force_{};
  std::atomic<bool> silent_{false}, vanished_{false};
  enum : int { kNoFault, kFaultPending, kFaultSaid };
  std::atomic<int> fault_{kNoFault};  // an injected device fault: the effect stopped for good
  std::atomic<std::int64_t> latency_ns_{0};
  std::atomic<std::uint64_t> updates_taken_{0};
  std::atomic<int> last_level_{0};
  std::deque<Pending> pending_;  // updates received and what came behind them, in order
  std::array<std::uint8_t, drivers::evdev::wire::kMaxMessage> rx_{};
  std::vector<std::uint8_t> tx_;
};

}  // namespace hapticd::sim::evdev
