#include "transport_rig.h"

#include <gtest/gtest.h>
#include <limits.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "config/config_loader.h"
#include "wiring/registry.h"

namespace hapticd::systemd_test {

config::Config load_config(const std::string& yaml, const std::string& path) {
  return config::load_config_text(yaml, path, {}, "/etc/hapticd", wiring::driver_schemas());
}

InstanceRules::InstanceRules(const Instance& instance, const std::string& trigger)
    : path_("/etc/udev/rules.d/70-hapticd-" + instance.name() + ".rules") {
  const Shell write = sh("hapticd udev-rules --config " + instance.config_path() + " >" + path_ +
                         " && cat " + path_ + " && udevadm control --reload");
  rules_ = write.out;
  if (write.status != 0) {
    error_ = "writing the rules: " + write.out;
    return;
  }
  const Shell t = sh("udevadm trigger --action=add " + trigger + " && udevadm settle --timeout=60");
  if (t.status != 0) error_ = "udevadm trigger " + trigger + ": " + t.out;
}

InstanceRules::~InstanceRules() {
  std::filesystem::remove(path_);
  sh("udevadm control --reload");
}

DropIn::DropIn(const Instance& instance, const std::string& text)
    : dir_("/etc/systemd/system/" + instance.unit() + ".d") {
  std::filesystem::create_directories(dir_);
  std::ofstream(dir_ + "/" + instance.name() + ".conf") << text;
  // An instance not loaded yet reads its drop-ins when it is; a daemon-reload, which takes
  // seconds in the emulated machine, only when systemd says it needs one.
  if (instance.property("NeedDaemonReload") == "yes") sh("systemctl daemon-reload");
}

// The instance is unloaded once it is stopped and its failure reset (Instance's end), and
// with it what it read of the drop-in.
DropIn::~DropIn() { std::filesystem::remove_all(dir_); }

SimulatedDevice::SimulatedDevice(const config::Config& cfg, const std::string& endpoint)
    : peer(wiring::find_driver(cfg.device.driver).peer.make_peer_on(cfg, endpoint)),
      runner(std::make_unique<sim::PeerRunner>(*peer, 70)) {}

SimulatedDevice::~SimulatedDevice() {
  runner->stop();
  EXPECT_EQ(runner->error(), "") << "the simulated device failed on its side";
  peer->stop();
}

long wait_for_contact(const Instance& instance, long ticks, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  long contact = 0;
  while (contact < ticks && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const Shell r = sh("hapticctl -i " + instance.name() + " --json status");
    const auto j = nlohmann::json::parse(r.out, nullptr, false);
    // The loop's count, from the run's counters (docs/operations.md#counters).
    const nlohmann::json::json_pointer at("/status/counters/loop/contact_ticks");
    if (j.is_object() && j.contains(at) && j[at].is_number()) contact = j[at].get<long>();
  }
  return contact;
}

void expect_clean_stop(const Instance& instance, const std::string& driver) {
  const Shell stop = instance.systemctl("stop");
  EXPECT_EQ(stop.status, 0) << stop.out;
  // Unloaded once stopped: systemd's word on how it ended is in the journal.
  const std::string j = instance.wait_journal("Deactivated successfully");
  std::cout << "$ journalctl -u " << instance.unit() << "\n" << j << "\n";
  EXPECT_FALSE(contains(j, "Main process exited")) << "logged for any exit but 0";
  EXPECT_TRUE(contains(j, "stopped by signal SIGTERM")) << j;
  EXPECT_TRUE(contains(j, "faults         none")) << j;
  EXPECT_TRUE(std::regex_search(
      j, std::regex("output         " + driver + " .*configured, disabled, last command 0 N")))
      << j;
  std::smatch m;
  EXPECT_TRUE(std::regex_search(j, m, std::regex("contact +([0-9]+) ticks")) && std::stol(m[1]) > 0)
      << "the wall was felt: " << j;
  EXPECT_TRUE(instance.journal("err").empty()) << instance.journal("err");
}

std::string GpioMachine::pwm_chip() const {
  return pwm.chip_path().substr(pwm.chip_path().rfind('/') + 1);
}

std::string GpioMachine::yaml() const {
  return config_text(
      "gpio.yaml",
      {"loop.rate_hz=50", "wall.stiffness=150", "device.gpio.counts_per_unit=2000",
       "device.sim.counts_per_unit=2000", "device.gpio.start_count=-4",
       "device.gpio.max_edge_rate=25", "loop.overrun_fault_streak=50",
       // tests/gpio/gpio_kernel_test.cpp: an encoder slower than the check's push.
       "safety.direction_check.max_latency_ms=300", "safety.direction_check.on_no_motion=run",
       "safety.stale_fault_ticks=10", "device.sim.initial_position=-0.00175",
       // The simulated device runs before the service starts (the direction check pushes a
       // plant at rest and sees it move); the hand presses once the service is up, seconds
       // into the emulated machine's start of it.
       "device.sim.operator.setpoint.rest=-0.00175", "device.sim.operator.setpoint.start=20",
       "device.sim.operator.setpoint.ramp=5", "device.sim.operator.setpoint.hold=600",
       // By number: a chip's label cannot be matched by a udev rule (docs/operations.md).
       "device.gpio.chip=" + chip.chip_name(), "device.gpio.pwm.chip=" + pwm_chip().substr(7)});
}

std::string GpioMachine::endpoint() const {
  char buf[PATH_MAX];
  const std::string link = "/sys/bus/gpio/devices/" + chip.chip_name();
  if (realpath(link.c_str(), buf) == nullptr) return "(no " + link + ")";
  return std::string(buf) + ",/sys/devices/platform/hapticd-pwm-sim/channel0";
}

std::string GpioMachine::drop_in() const {
  char buf[PATH_MAX];
  const std::string dir = realpath(pwm.chip_path().c_str(), buf) != nullptr ? buf : "";
  return "[Service]\nReadWritePaths=" + dir + "\n";
}

std::string GpioMachine::trigger() const {
  return "--subsystem-match=gpio --subsystem-match=pwm --sysname-match=" + chip.chip_name() +
         " --sysname-match=" + pwm_chip();
}

}  // namespace hapticd::systemd_test
