// The GPIO driver's simulated device (docs/drivers/gpio.md): a motor driver and a quadrature
// encoder with the plant between them (encoder_sim.h), on one of two carriers:
//   - GpioLoopbackPeer: the driver's socketpair (gpio_wire.h), in hapticd's own process. It
//     steps the plant once per output message (the driver sends one a tick: the PWM period's
//     clock) and answers with the period's edges, time-stamped on the plant's clock, in freerun
//     and real-time runs alike: a simulated device in the same process keeps time by its
//     protocol, not the wall clock (sim/peers/peer_runner.h), so neither hapticd's start-up
//     nor a host that holds its threads up moves the plant without the loop.
//   - GpioKernelPeer: a gpio-sim chip and the PWM simulator in the kernel test machine. It
//     steps the plant on its own timer every period, reads the PWM channel's applied state and
//     the direction line, and puts each edge on the wires at its time by writing the gpio-sim
//     lines' `pull` attributes; the kernel time-stamps them as it would real edges.
// Both also inject the GPIO wire faults (WireFault) besides the generic PeerFault ones. A device
// of several joints (device.gpio.joints) has an encoder and a motor driver per joint, moving
// one simulated mechanism (sim/mechanism.h) together.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "config/config.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/gpio/encoder_sim.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_state.h"

namespace hapticd::sim::gpio {

class GpioPeer : public LoopbackPeer {
 public:
  // Any thread. Produce `f` once on joint `joint`'s wires, from the next period on.
  virtual bool inject_wire(WireFault f, std::size_t joint = 0) noexcept = 0;
  // Any thread. PeerFault::kDeviceFault raises joint `joint`'s fault line from now on (false
  // without one); inject(kDeviceFault) raises the first joint's that has one.
  virtual bool inject_fault_line(std::size_t joint) noexcept = 0;
  // Any thread. Whether every joint's PWM channel was enabled at the last output the peer
  // applied.
  virtual bool channel_enabled() const noexcept = 0;
  // Any thread. Joint `joint`'s duty at the last output the peer applied (0 while its motor
  // driver is in fault).
  virtual std::uint64_t duty_ns(std::size_t joint) const noexcept = 0;
};

// What both peers publish of their joints for other threads.
class PublishedJoints {
 public:
  void publish(const JointEncoders& enc) noexcept {
    for (std::size_t j = 0; j < enc.size(); ++j) duty_[j].store(enc[j].duty_ns());
    enabled_.store(enc.channel_enabled());
  }
  std::uint64_t duty_ns(std::size_t joint) const noexcept {
    return joint < duty_.size() ? duty_[joint].load() : 0;
  }
  bool channel_enabled() const noexcept { return enabled_.load(); }

 private:
  std::array<std::atomic<std::uint64_t>, dg::wire::kMaxJoints> duty_{};
  std::atomic<bool> enabled_{false};
};

// Throws config::ConfigError when device.sim and device.gpio disagree about the encoder (the
// peer simulates the encoder device.gpio describes: resolution and start count must match).
std::unique_ptr<GpioPeer> make_loopback_peer(const config::Config& cfg, io::UniqueFd fd);
// `endpoint`: "GPIO_SIM_CHIP_SYSFS_DIR,PWM_SIM_CHANNEL_FILE", e.g.
// "/sys/devices/platform/gpio-sim.0/gpiochip1,/sys/devices/platform/hapticd-pwm-sim/channel0".
// Throws DeviceError when they cannot be opened.
std::unique_ptr<GpioPeer> make_kernel_peer(const config::Config& cfg, const std::string& endpoint);

}  // namespace hapticd::sim::gpio
