// Issue 34, 6: a device in user space slow to answer each update (UI_BEGIN_FF_UPLOAD /
// UI_END_FF_UPLOAD) must cost delay, not the loop. The driver against its simulated device
// told to take each update 15 ms after it came, the loop at 100 Hz in real time, not paced (a
// paced loopback waits for the device's every answer, sim/peers/paced_device.h): EVIOCSFF's
// stand-in blocks until that answer, so with the update on the loop's thread every tick
// overran and the loop faulted after loop.overrun_fault_streak of them. With the update thread
// the loop keeps time, the device takes about every other level (the newest), and the delay
// is what the configuration declares; a device slower than declared faults, named.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "config/config_loader.h"
#include "control/controller.h"
#include "device_counter.h"
#include "loop/servo_loop.h"
#include "sim/peers/evdev/evdev_peer.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::evdev {
namespace {

using hapticd::testing::counter_value;
using namespace std::chrono_literals;

constexpr auto kAnswer = 15ms;  // what the simulated device takes per update

// config/evdev.yaml as a uinput device at 100 Hz, its wall soft enough for the delay declared.
config::Config slow_config(const std::string& latency_ms) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/evdev.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> sets;
  const std::vector<std::string> overrides = {"loop.rate_hz=100",
                                              "loop.clock=realtime",
                                              "device.evdev.ff_driver=uinput",
                                              "device.evdev.poll_interval_ms=",
                                              "device.evdev.update_latency_ms=" + latency_ms,
                                              "wall.stiffness=30"};
  for (const std::string& s : overrides) {
    sets.push_back(config::parse_override(s));
  }
  return config::load_config_text(text.str(), "evdev.yaml", sets, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

// The driver and its simulated device on its own thread, taking each update kAnswer late.
struct SlowRig {
  explicit SlowRig(const std::string& latency_ms)
      : cfg(slow_config(latency_ms)), pair(wiring::find_driver("evdev").make_loopback(cfg)) {
    peer().take_updates_after(kAnswer);
    runner = std::make_unique<sim::PeerRunner>(*pair.peer);
  }
  ~SlowRig() {
    pair.device->close();
    runner.reset();
  }
  sim::evdev::SocketEvdevPeer& peer() {
    return dynamic_cast<sim::evdev::SocketEvdevPeer&>(*pair.peer);
  }
  Device& device() { return *pair.device; }
  loop::LoopResult run(std::uint64_t ticks) {
    control::Controller controller(control::make_control_law(cfg));
    loop::LoopOptions o;
    o.realtime = true;
    o.period_ns = std::llround(cfg.loop.sample_period_s() * 1e9);
    o.overrun_fault_streak = cfg.loop.overrun_fault_streak;
    o.stale_fault_ticks = cfg.safety.stale_fault_ticks;
    o.max_speed = cfg.safety.max_speed;
    o.max_ticks = ticks;
    loop::ServoLoop servo(device(), controller, nullptr, o);
    const std::atomic<bool> stop{false};
    return servo.run(stop);
  }
  config::Config cfg;
  wiring::Loopback pair;
  std::unique_ptr<sim::PeerRunner> runner;
};

bool eventually(const std::function<bool()>& what, std::chrono::milliseconds within) {
  const auto end = std::chrono::steady_clock::now() + within;
  while (!what()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

TEST(EvdevSlowDevice, ADeviceTakingFifteenMsPerUpdateCostsDelayNotTheLoop) {
  SlowRig rig("25");
  rig.device().configure();
  EXPECT_EQ(rig.device().info().transport_delay_samples, 4) << "ceil(2 x 25 ms / 10 ms) - 1";
  rig.device().enable();
  const loop::LoopResult r = rig.run(200);
  EXPECT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
  EXPECT_EQ(r.ticks, 200u);
  const Device& d = rig.device();
  const std::uint64_t taken = counter_value(d, "effect_updates");
  const std::uint64_t superseded = counter_value(d, "updates_superseded");
  RecordProperty("overruns", std::to_string(r.overruns));
  RecordProperty("effect_updates", std::to_string(taken));
  RecordProperty("updates_superseded", std::to_string(superseded));
  RecordProperty("longest_update_us", std::to_string(counter_value(d, "longest_update_us")));
  EXPECT_LT(r.overruns, 10u) << "the loop kept time";
  // One update every 15 ms and a little, at most: about every other tick's level.
  EXPECT_GT(taken, 60u);
  EXPECT_LT(taken, 150u);
  EXPECT_GT(superseded, 50u) << "the levels the device was too busy for";
  EXPECT_GE(counter_value(d, "longest_update_us"), 15'000u);
  EXPECT_EQ(counter_value(d, "late_updates"), 0u) << "within the 25 ms declared";
  EXPECT_GE(rig.peer().updates_taken(), taken);
}

// Declared as a device that answers at once (update_latency_ms 0: half a period, 5 ms,
// covered), the same device is late at every update: late_update_fault of them in a row end
// the run with zero force, the cause named with the key to change.
TEST(EvdevSlowDevice, ADeviceSlowerThanDeclaredFaultsTheRunNamingTheKey) {
  SlowRig rig("0");
  rig.device().configure();
  EXPECT_EQ(rig.device().info().transport_delay_samples, 0);
  rig.device().enable();
  const loop::LoopResult r = rig.run(200);
  EXPECT_EQ(r.fault.cause, loop::FaultCause::kTransportWrite) << loop::describe(r.fault);
  EXPECT_LT(r.ticks, 20u) << "three late updates, about 45 ms";
  const std::string why = rig.device().describe_fault();
  EXPECT_NE(why.find("longer than the 5.0 ms the declared delay covers"), std::string::npos) << why;
  EXPECT_NE(why.find("device.evdev.update_latency_ms 0"), std::string::npos) << why;
  EXPECT_GE(counter_value(rig.device(), "late_updates"), 3u);
  rig.device().disable();
  EXPECT_TRUE(eventually([&] { return !rig.peer().output_on(); }, 1s));
  EXPECT_EQ(rig.peer().applied_force(), 0.0);
}

// The crash handler's stop and disable's are EV_FF writes: the device stops at once, while the
// update it has in hand (200 ms) is still to be answered; level 0 follows that update.
TEST(EvdevSlowDevice, TheStopsReachTheDeviceAheadOfTheUpdateItHasInHand) {
  for (const bool emergency : {true, false}) {
    SCOPED_TRACE(emergency ? "emergency_stop" : "disable");
    SlowRig rig("210");
    rig.peer().take_updates_after(0ms);
    rig.device().configure();
    rig.device().enable();
    ASSERT_TRUE(eventually([&] { return rig.peer().output_on(); }, 1s));
    rig.peer().take_updates_after(200ms);
    const std::uint64_t taken = rig.peer().updates_taken();
    ASSERT_EQ(rig.device().write(2.0), IoStatus::kOk);
    std::this_thread::sleep_for(20ms);  // the update is with the device now
    const auto t0 = std::chrono::steady_clock::now();
    std::thread stopping([&] {
      if (emergency) {
        rig.device().emergency_stop();
      } else {
        rig.device().disable();  // waits for the update in hand before erasing the effect
      }
    });
    EXPECT_TRUE(eventually([&] { return !rig.peer().output_on(); }, 100ms))
        << "the device still plays";
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 150ms);
    EXPECT_EQ(rig.peer().updates_taken(), taken) << "stopped before the update was taken";
    EXPECT_EQ(rig.peer().applied_force(), 0.0);
    stopping.join();
  }
}

}  // namespace
}  // namespace hapticd::drivers::evdev
