// The transports under systemd: an instance's udev rules written by `hapticd udev-rules` and
// applied by the machine's udevd, the simulated device on the kernel interface (this
// process's, as the kernel tests run it), and what a clean run of the instance leaves in its
// journal.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "config/config.h"
#include "gpio_sim_chip.h"
#include "pwm_sim.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_runner.h"
#include "systemd_rig.h"

namespace hapticd::systemd_test {

// The configuration hapticd reads, loaded the same way for the simulated device.
config::Config load_config(const std::string& yaml, const std::string& path);

// /etc/udev/rules.d/70-hapticd-NAME.rules from `hapticd udev-rules --config`, udevd told,
// and the devices of `trigger` (udevadm trigger's matches) replayed; removed at the end.
class InstanceRules {
 public:
  InstanceRules(const Instance& instance, const std::string& trigger);
  ~InstanceRules();
  InstanceRules(const InstanceRules&) = delete;
  InstanceRules& operator=(const InstanceRules&) = delete;
  const std::string& error() const { return error_; }  // "" when all of it worked
  const std::string& rules() const { return rules_; }

 private:
  std::string path_, rules_, error_;
};

// A drop-in for hapticd@NAME (/etc/systemd/system/hapticd@NAME.service.d/NAME.conf), as
// `systemctl edit` writes one, and systemd told; removed at the end.
class DropIn {
 public:
  DropIn(const Instance& instance, const std::string& text);
  ~DropIn();
  DropIn(const DropIn&) = delete;
  DropIn& operator=(const DropIn&) = delete;

 private:
  std::string dir_;
};

// The simulated device on its kernel endpoint, serviced by its own thread.
struct SimulatedDevice {
  SimulatedDevice(const config::Config& cfg, const std::string& endpoint);
  ~SimulatedDevice();
  std::unique_ptr<sim::LoopbackPeer> peer;
  std::unique_ptr<sim::PeerRunner> runner;
};

// Waits (up to `timeout`) until `hapticctl -i NAME status` counts `ticks` ticks in contact;
// returns the count read then (at least `ticks`, or less at the time-out).
long wait_for_contact(const Instance& instance, long ticks,
                      std::chrono::milliseconds timeout = std::chrono::seconds(30));

// The instance's clean stop, from its journal: SIGTERM, exit 0, the wall felt, no fault, the
// driver's output disabled at zero.
void expect_clean_stop(const Instance& instance, const std::string& driver);

// gpio-sim's chip and hapticd's PWM simulator, with the configuration that drives them at the
// rate the machine sustains (tests/gpio/gpio_kernel_test.cpp says why each number).
struct GpioMachine {
  kernel_test::GpioSimChip chip{5, "hapticd-sd-gpio", {}, "hapticd-sd"};
  kernel_test::PwmSim pwm;
  std::string pwm_chip() const;  // pwmchipN
  std::string yaml() const;
  std::string endpoint() const;  // the peer's: the chip's sysfs directory, the PWM channel
  // The drop-in a GPIO instance needs: its PWM chip's device directory writable.
  std::string drop_in() const;
  std::string trigger() const;  // the chip and the PWM chip, for InstanceRules
};

}  // namespace hapticd::systemd_test
