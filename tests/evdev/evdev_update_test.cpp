// The evdev driver's update thread (drivers/evdev/update_thread.h) against a scripted transport
// whose updates take as long as a slow device in user space takes to answer: write() hands the
// level on without waiting, the newest level wins, what the update thread measures is judged
// against what the declared delay covers, and a stop never waits behind an update in hand. And
// an axis whose value is a counter that wraps, unwrapped.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "device_counter.h"
#include "device_rig.h"

namespace hapticd::drivers::evdev {
namespace {

using hapticd::testing::counter_value;
using testing::Rig;
using Clock = std::chrono::steady_clock;

bool eventually(const std::function<bool()>& what) {
  const auto end = Clock::now() + std::chrono::seconds(5);
  while (!what()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// At 1 kHz a device that takes 20 ms per update is declared so (update_latency_ms 30): the
// writes do not wait for it, the levels it was too busy for are superseded, and the newest
// reaches it.
TEST(EvdevUpdates, ASlowDeviceIsNotWaitedForAndTheNewestLevelWins) {
  Rig r([](EvdevSettings& s) {
    s.ff_driver = FfDriver::kUinput;
    s.update_latency_ms = 30.0;
  });
  r.script->update_delay = std::chrono::milliseconds(20);
  r.device->configure();
  EXPECT_EQ(r.device->info().transport_delay_samples, 59) << "ceil(2 L / T) - 1";
  r.device->enable();
  const std::uint64_t taken_before = counter_value(*r.device, "effect_updates");
  Clock::duration slowest{};
  for (int i = 1; i <= 10; ++i) {
    const auto t0 = Clock::now();
    ASSERT_EQ(r.device->write(0.5 * i), IoStatus::kOk);
    slowest = std::max(slowest, Clock::now() - t0);
  }
  EXPECT_LT(slowest, std::chrono::milliseconds(5)) << "a write waited for the device";
  r.device->wait_output();
  EXPECT_EQ(r.script->levels.back(), 16384) << "the newest level, 5 N of 10";
  const std::uint64_t taken = counter_value(*r.device, "effect_updates") - taken_before;
  EXPECT_LE(taken, 3u) << "the device took one at a time, 20 ms each";
  EXPECT_EQ(counter_value(*r.device, "updates_superseded"), 10 - taken);
  EXPECT_GE(counter_value(*r.device, "longest_update_us"), 20'000u);
  EXPECT_EQ(counter_value(*r.device, "late_updates"), 0u) << "within the 30 ms declared";
}

// Declared as fast (update_latency_ms 0: half a period, 0.5 ms, covered), a device that takes
// 5 ms per update is late: each one counted, one alone forgiven, late_update_fault in a row the
// run's transport fault, named with what was measured and the key to raise.
TEST(EvdevUpdates, UpdatesLongerThanTheDeclaredDelayCoversAreCountedAndARunOfThemFaults) {
  Rig r([](EvdevSettings& s) { s.late_update_fault = 3; });
  r.device->configure();
  r.device->enable();
  r.script->update_delay = std::chrono::milliseconds(5);
  ASSERT_EQ(r.device->write(1.0), IoStatus::kOk);
  r.device->wait_output();
  r.script->update_delay = std::chrono::milliseconds(0);
  ASSERT_EQ(r.device->write(1.0), IoStatus::kOk);
  r.device->wait_output();
  ASSERT_EQ(r.device->write(1.0), IoStatus::kOk) << "one late update alone is no fault";
  r.device->wait_output();
  EXPECT_EQ(counter_value(*r.device, "late_updates"), 1u);
  r.script->update_delay = std::chrono::milliseconds(5);
  int writes = 0;
  IoStatus w = IoStatus::kOk;
  for (; writes < 10 && w == IoStatus::kOk; ++writes) {
    r.device->wait_output();
    w = r.device->write(1.0);
  }
  EXPECT_EQ(w, IoStatus::kTransportFault);
  EXPECT_EQ(writes, 4) << "three late updates, then the write that sees them";
  r.device->wait_output();
  EXPECT_EQ(counter_value(*r.device, "late_updates"), 5u) << "and the fault's level 0, late too";
  const std::string why = r.device->describe_fault();
  EXPECT_NE(why.find("3 in a row longer than the 0.5 ms the declared delay covers"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("device.evdev.update_latency_ms 0"), std::string::npos) << why;
  EXPECT_NE(why.find("the device took up to "), std::string::npos) << why;
  EXPECT_GE(counter_value(*r.device, "longest_update_us"), 5000u);
}

// In freerun (loop.clock freerun: the conformance suite, `replay`) nothing waits on the clock,
// so an update's wall time makes nothing late: a loaded host (a sanitizer build beside another
// test) no longer faults the run, and the longest update is still counted.
TEST(EvdevUpdates, InFreerunNoUpdateIsLateHoweverLong) {
  Rig r(
      0.0, {}, [](EvdevSettings& s) { s.late_update_fault = 3; }, false);
  r.device->configure();
  r.device->enable();
  r.script->update_delay = std::chrono::milliseconds(5);
  for (int writes = 0; writes < 8; ++writes) {
    r.device->wait_output();
    ASSERT_EQ(r.device->write(1.0), IoStatus::kOk) << "write " << writes;
  }
  r.device->wait_output();
  EXPECT_EQ(counter_value(*r.device, "late_updates"), 0u);
  EXPECT_GE(counter_value(*r.device, "longest_update_us"), 5000u);
}

// The kernel lets nothing through the node while an EVIOCSFF is in hand (evdev's mutex), so a
// fault's stop is the update thread's: the RT thread that sees the fault returns at once, the
// stop follows the 200 ms update in hand, and level 0 follows the stop - never the level that
// was waiting.
TEST(EvdevUpdates, AFaultsStopFollowsTheUpdateInHandAheadOfTheLevelWaiting) {
  Rig r([](EvdevSettings& s) { s.update_latency_ms = 250.0; });
  r.device->configure();
  r.device->enable();
  r.script->update_delay = std::chrono::milliseconds(200);
  ASSERT_EQ(r.device->write(5.0), IoStatus::kOk);
  ASSERT_TRUE(eventually([&] { return r.script->updating.load() == 1; }));
  ASSERT_EQ(r.device->write(2.5), IoStatus::kOk) << "waiting behind the update in hand";
  const auto t0 = Clock::now();
  r.script->read_error = ENODEV;
  PositionSample s;
  EXPECT_EQ(r.device->read(s), IoStatus::kTransportFault);
  EXPECT_LT(Clock::now() - t0, std::chrono::milliseconds(50)) << "the RT thread waited";
  EXPECT_EQ(r.script->updating.load(), 1) << "the update is still in hand";
  r.device->wait_output();
  const std::vector<std::string> tail(r.script->calls.end() - 3, r.script->calls.end());
  EXPECT_EQ(tail, (std::vector<std::string>{"update 16384", "write 3 0", "update 0"}))
      << "the 2.5 N level (8192) never went out";
  EXPECT_EQ(counter_value(*r.device, "updates_superseded"), 1u);
  r.device->emergency_stop();  // the crash handler's: the transport's own write(2)
  EXPECT_EQ(r.script->emergencies.load(), 1);
}

// A device reporting a counter of its report field's width (16 bits: [-32768, 32767]) passes
// 32767 and continues at -32768: with axis.wraps the position goes on past the range's end.
TEST(EvdevUpdates, AnAxisThatWrapsIsUnwrappedFromThePreviousSample) {
  const auto wraps = [](EvdevSettings& s) { s.axis.wraps = true; };
  Rig r(wraps);
  r.script->facts.range = {-32768, 32767, 0};
  r.script->facts.value = 32700;
  r.device->configure();
  r.device->enable();
  const double count = 0.1 / 65535.0;  // m per count
  PositionSample s;
  r.frame(32760);
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  const double before = s.position;
  r.frame(-32736);  // 40 counts on: 32767, then -32768 and 31 more
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position - before, 40 * count, 1e-12) << "past the range's maximum";
  r.frame(32767);  // and back the other way across it
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position - before, 7 * count, 1e-12);

  Rig plain;
  plain.script->facts.range = {-32768, 32767, 0};
  plain.script->facts.value = 32760;
  plain.device->configure();
  plain.device->enable();
  plain.frame(-32736);
  ASSERT_EQ(plain.device->read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position, -0.05 + 32 * count, 1e-12) << "without wraps: the value as it is";

  Rig odd(wraps);  // 2001 values: no counter's width
  try {
    odd.device->configure();
    ADD_FAILURE() << "a range of 2001 values was taken for a counter";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("device.evdev.axis.wraps needs a counter's range"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hapticd::drivers::evdev
