// What the kernel tests against the reference drives share (can_reference_kernel_test.cpp,
// can_reference_real_drive_kernel_test.cpp): `hapticd run` at rates an emulated guest keeps,
// the hand that pushes once output is on, the wait for the direction check, the rest measured.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "child_process.h"
#include "reference/can/odrive_056.h"
#include "reference/can/reference_plant.h"
#include "reference/can/reference_runner.h"

namespace hapticd::drivers::can::testing {

using std::chrono::milliseconds;
using std::chrono::seconds;

inline const std::string kBin = HAPTICD_BINARY;
// An emulated guest cannot keep 1 kHz, and stalls now and then (over 150 ms was seen under a
// loaded host): the ODrive at 50 Hz, the CiA 402 drives at 5 Hz (a SYNC-watching drive times
// out after 1.5 cycles: 300 ms), each with a wall the gate passes there with the driver's one
// sample of delay, and a hand pushing F into it: the rest is F/K = 20 mm.
struct Rig {
  double rate_hz, stiffness, hand_force;
};
constexpr Rig kOdriveRig{50.0, 50.0, 1.0};
constexpr Rig kCia402Rig{5.0, 5.0, 0.1};

inline std::vector<std::string> run_args(const std::string& profile, double duration,
                                         std::vector<std::string> sets) {
  const Rig& r = profile == "odrive" ? kOdriveRig : kCia402Rig;
  std::vector<std::string> a = {
      kBin,         "run",
      "--config",   std::string(HAPTICD_SOURCE_DIR) + "/config/can-" + profile + ".yaml",
      "--duration", std::to_string(duration)};
  sets.push_back("loop.rate_hz=" + std::to_string(r.rate_hz));
  if (profile == "cia402") {  // hapticd's heartbeat each tick, watched over several
    sets.push_back("device.can.cia402.master_heartbeat_ms=200");
    sets.push_back("device.can.cia402.drive_watchdog_ms=1500");
  }
  for (const char* s : {"safety.stale_fault_ticks=10", "loop.overrun_fault_streak=100",
                        "safety.direction_check.max_latency_ms=300", "device.can.interface=vcan0",
                        "device.can.sdo_timeout_ms=1000", "device.can.state_timeout_ms=2000",
                        "device.can.heartbeat_timeout_ms=3000"}) {
    sets.push_back(s);
  }
  sets.push_back("wall.stiffness=" + std::to_string(r.stiffness));
  for (const std::string& s : sets) a.insert(a.end(), {"--set", s});
  return a;
}

// `hapticd run` on config/can-gantry.yaml over vcan0 at the rig's rate, with the rig's wall
// along the diagonal through the origin, the emulator's slack in the timeouts, and `sets`.
inline std::vector<std::string> gantry_args(const Rig& rig, std::vector<std::string> sets) {
  std::vector<std::string> a = {
      kBin,         "run", "--config", std::string(HAPTICD_SOURCE_DIR) + "/config/can-gantry.yaml",
      "--duration", "60"};
  for (const std::string& set :
       {std::string("loop.rate_hz=") + std::to_string(rig.rate_hz),
        std::string("device.can.interface=vcan0"), std::string("device.can.sdo_timeout_ms=1000"),
        std::string("device.can.state_timeout_ms=2000"),
        std::string("device.can.heartbeat_timeout_ms=3000"),
        std::string("safety.stale_fault_ticks=10"), std::string("loop.overrun_fault_streak=100"),
        "walls=[{point: [0, 0], normal: [1, 1], damping: 0, stiffness: " +
            std::to_string(rig.stiffness) + "}]"}) {
    sets.push_back(set);
  }
  for (const std::string& set : sets) a.insert(a.end(), {"--set", set});
  return a;
}

// config/can-gantry.yaml's CiA 402 nodes as two ODrive 0.5 axes (node 1 x, node 2 y), each
// transmission the reference axis's, the watchdog the emulator's slow start needs.
inline std::vector<std::string> odrive_gantry_sets() {
  return {"device.can.profile=odrive",
          "device.can.cia402=null",
          "device.can.torque_per_force=0.015625",
          "device.can.position_per_unit=0.09817477042468103",
          "device.can.max_torque=0.15625",
          "device.can.nodes=[{node_id: 1}, {node_id: 2}]",
          "device.can.odrive.watchdog_timeout_s=1",
          "device.can.odrive.vel_limit=2"};
}

// Two ODrive 0.5 reference axes on vcan0, nodes 1 and 2 (x and y of odrive_gantry_sets()),
// each pushed by its own hand of `hand_force` once pressed, each served by its own runner.
struct OdriveGantryAxes {
  explicit OdriveGantryAxes(double hand_force);
  std::vector<std::unique_ptr<reference::Odrive056>> axes;
  std::vector<std::unique_ptr<reference::ReferenceRunner>> runners;
};

// The hand pushes once hapticd has output on (press_now): a wall that finds the axis already
// inside it stays off until the axis leaves it.
inline reference::PlantParameters hand(double force, double damping) {
  reference::PlantParameters p;
  p.damping = damping;
  p.hand_force = force;
  p.hand_start_s = 1e6;
  p.hand_ramp_s = 0.5;
  return p;
}

inline OdriveGantryAxes::OdriveGantryAxes(double hand_force) {
  for (const std::uint8_t node : {1, 2}) {
    reference::Odrive056Config c;
    c.node = node;
    c.watchdog_timeout_s = 1.0;  // the emulator's slow start of the RT thread
    axes.push_back(std::make_unique<reference::Odrive056>(c, hand(hand_force, 10.0),
                                                          reference::monotonic_ns()));
    runners.push_back(std::make_unique<reference::ReferenceRunner>(
        *axes.back(), reference::CanPort::open("vcan0")));
  }
}

// The axis at rest against the wall: the mean position over the last `ms` before now.
template <typename Drive>
double rest_position(const Drive& drive, int ms) {
  double sum = 0.0;
  int n = 0;
  for (int i = 0; i < ms / 10; ++i) {
    sum += drive.position_m();
    ++n;
    std::this_thread::sleep_for(milliseconds(10));
  }
  return sum / n;
}

// Until the run's direction check has armed the wall (its log line), or `timeout`; false then.
// A hand that pushes before it would keep the device from the rest the check waits for.
inline bool wait_for_armed_wall(const ChildProcess& run, milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (run.output().find("direction check: confirmed") != std::string::npos) return true;
    std::this_thread::sleep_for(milliseconds(50));
  }
  return false;
}

}  // namespace hapticd::drivers::can::testing
