// What the HID kernel tests share: the simulated device in this process on a real kernel
// endpoint (a USB HID gadget's /dev/hidgN, or /dev/uhid), and `hapticd run` as the user runs
// it, in its own process, through hidapi and the kernel's usbhid/hidraw or libusb.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "hapticd_process.h"
#include "hid_test_support.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::hid::testing {

// What the kernel tests change in the example configurations. The machine is emulated (TCG,
// on a shared host) and its USB controller is dummy_hcd, which moves transfers on a 4 ms
// kernel timer (HZ 250); wake-ups there come up to 50 ms late. At 100 Hz a command and its
// answer fit one period, so the driver declares 0 samples (1 ms polling; at 1 kHz on hardware
// the same code declares 1), and the wall is made soft enough for the gate at that rate. The
// emulator's stalls make answers late (a stale tick, then two answers at once: a gap of one),
// which the production thresholds would rightly call a fault: here the thresholds sit above
// what the emulator does and below what the injected faults do (silence for good, a jump of
// 50 sequence numbers, a status bit). The direction check looks for the push's motion up to
// 300 ms later than declared (the emulated USB controller's transfers wait that long), and the
// simulated hand presses 1.5 s into the run (the peer's clock starts with hapticd's first
// report), once the check has armed the wall.
inline const std::vector<std::string> kKernelRate = {"loop.rate_hz=100",
                                                     "wall.stiffness=250",
                                                     "wall.damping=0.2",
                                                     "safety.stale_fault_ticks=50",
                                                     "safety.sequence_gap_fault=20",
                                                     "loop.overrun_fault_streak=1000",
                                                     "safety.direction_check.max_latency_ms=300",
                                                     "device.sim.operator.setpoint.start=1.5"};

// `hapticd` in its own process, as the reference devices' tests run it.
using Hapticd = reference::HapticdRun;
using reference::run_hapticd;

inline std::vector<std::string> with_sets(std::vector<std::string> args,
                                          const std::vector<std::string>& sets) {
  for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
  return args;
}

// The simulated device on `endpoint`, serviced by its own thread as firmware runs.
struct KernelPeer {
  KernelPeer(const config::Config& cfg, const std::string& endpoint)
      : peer(wiring::find_driver("hid").peer.make_peer_on(cfg, endpoint)), runner(*peer, 70) {}
  // The simulated device must not have failed on its side (a transfer error, a thread that
  // died): its watchdog would have stopped with it.
  ~KernelPeer() {
    runner.stop();
    EXPECT_EQ(runner.error(), "") << "the simulated device failed";
    peer->stop();
  }
  // Waits (up to `timeout`) until `predicate` holds; false if it never did.
  static bool wait_for(const std::function<bool()>& predicate,
                       std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      if (predicate()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return predicate();
  }
  std::unique_ptr<sim::LoopbackPeer> peer;
  sim::PeerRunner runner;
};

inline const std::string kKernelSerial = "hapticd-hid-kt";

// config/NAME in the source tree.
std::string example(const char* name);
// kKernelRate, the backend, selection by kKernelSerial, then `more`.
std::vector<std::string> sets_for(const char* backend, std::vector<std::string> more = {});
// The run summary's faults as JSON text; a run that wrote no summary says so.
std::string faults(const Hapticd& h);
// Waits until a device with kKernelSerial is listed by the hidraw backend (`present`), or is
// no longer listed; false if it never was.
bool wait_listed(bool present);

// `hapticd run` of `config` and the sim driver's run of the same plant and wall with the HID
// driver's declared delay as its own: the wall must feel the same (penetration within 10 %),
// with contact reached and no fault, and the run leaves the amplifier off.
void expect_the_sim_drivers_wall(const char* config, const std::vector<std::string>& sets,
                                 const sim::LoopbackPeer& peer);
// `sets` for a run that tries a fault: the direction check arms the wall unchecked when it
// cannot tell the emulated USB's motion from noise (kernel_rig.cpp).
std::vector<std::string> unchecked(std::vector<std::string> sets);
// A fault the device produces while the wall pushes: `hapticd run` commands zero, exits 1 and
// names the cause (`words`, a regular expression).
void expect_fault_exit(const char* config, const std::vector<std::string>& sets,
                       sim::LoopbackPeer& peer, sim::PeerFault fault, const std::string& words);
// SIGKILL leaves hapticd no chance to disable: the device's own watchdog (the report
// firmware's keep-alive, the PID effect's duration) must drop the force within `watchdog`.
void expect_no_force_after_sigkill(
    const char* config, const std::vector<std::string>& sets, sim::LoopbackPeer& peer,
    std::chrono::milliseconds watchdog = std::chrono::milliseconds(1000));

}  // namespace hapticd::drivers::hid::testing
