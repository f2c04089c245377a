// The CiA 402 profile against the reference drive (tests/reference/can/cia402_drive.h) doing
// what real drives do (issue 34): a 0x6064 that rolls over at 2^31 (an offset the drive keeps),
// a DC link that charges after mains on, and mains that never come.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <future>

#include "reference/can/cia402_drive.h"
#include "reference_rig.h"

namespace hapticd::drivers::can::testing {
namespace {

using reference::Cia402Behaviour;
using reference::Cia402Drive;

constexpr double kMetresPerCount = 1e-5;       // the example's position_per_unit
constexpr double kWrap = 2147483648.0 * 1e-5;  // 2^31 counts, in metres
constexpr std::int64_t kStartCount = -2000;    // the plant starts at -20 mm

// Ticking on a shared, loaded host: a cycle long enough that the drive's 1.5-cycle SYNC watch
// and its heartbeat consumer judge the driver, not the host (as can_reference_cia402_test.cpp).
config::Config slow_config(std::vector<std::string> sets = {}) {
  for (const char* s :
       {"loop.rate_hz=10", "wall.stiffness=10", "device.can.cia402.master_heartbeat_ms=100",
        "device.can.cia402.drive_watchdog_ms=1000", "device.can.heartbeat_timeout_ms=1000"}) {
    sets.emplace_back(s);
  }
  return load_example("can-cia402.yaml", sets, false);
}

// Issue 34, 1: 300 counts below 2^31 - 1 at the start, pushed up across the rollover and back
// down across it: the samples follow the axis, never a jump of 2^32 counts.
TEST(CanReferenceRealDrive, A0x6064ThatRollsOverBothWaysIsFollowed) {
  Cia402Behaviour b;
  b.position_offset = 2147483648LL - 300 - kStartCount;
  Cia402Drive drive(b, damped_axis(), reference::monotonic_ns());
  ReferenceRig rig(slow_config(), drive);
  rig.device->configure();
  rig.device->enable();
  ASSERT_EQ(rig.run(1.0, 800), IoStatus::kOk) << rig.device->describe_fault();
  ASSERT_EQ(rig.run(-1.0, 1500), IoStatus::kOk) << rig.device->describe_fault();
  ASSERT_GT(rig.samples.size(), 15u);
  bool above = false;
  for (std::size_t i = 1; i < rig.samples.size(); ++i) {
    // 0.1 m/s at 10 Hz: 10 mm a sample; the rollover taken as it is would be 42 949 m.
    ASSERT_LT(std::abs(rig.samples[i].position - rig.samples[i - 1].position), 0.03)
        << "sample " << i << ": " << rig.samples[i - 1].position << " -> "
        << rig.samples[i].position;
    above = above || rig.samples[i].position > kWrap + 5e-3;
  }
  EXPECT_NEAR(rig.samples.front().position, kWrap - 300 * kMetresPerCount, 50 * kMetresPerCount)
      << "the first sample is the count as sent";
  EXPECT_TRUE(above) << "went past 2^31";
  EXPECT_LT(rig.samples.back().position, kWrap) << "and came back below it";
  // Where the drive's axis is: the offset plus its position, in the same frame, read a moment
  // after the last sample while the drive's own thread moves it on (10 mm a sample period: up
  // to five periods on a loaded host, 20.4 mm seen on one).
  EXPECT_NEAR(rig.samples.back().position,
              static_cast<double>(b.position_offset) * kMetresPerCount + drive.position_m(), 0.05);
}

std::string enable_error(ReferenceRig& rig) {
  try {
    rig.device->enable();
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

// Issue 34, 2: mains come on while hapticd enables: the shutdown command waits for the DC link
// (800 ms, beyond state_timeout_ms 500), bit 4 at 0 meanwhile, and then the drive runs.
TEST(CanReferenceRealDrive, ADriveWhoseDcLinkChargesAfterMainsOnIsEnabled) {
  Cia402Behaviour b;
  b.mains_on_at_start = false;
  b.dc_link_charge_ms = 800;
  Cia402Drive drive(b, damped_axis(), reference::monotonic_ns());
  ReferenceRig rig(slow_config(), drive);
  rig.device->configure();
  auto enabled = std::async(std::launch::async, [&] { return enable_error(rig); });
  for (int i = 0; i < 200 && drive.dc_link_refusals() == 0; ++i) sleep_ms(5);
  ASSERT_GT(drive.dc_link_refusals(), 0) << "hapticd asked before the DC link was charged";
  drive.switch_mains_on();
  EXPECT_EQ(enabled.get(), "");
  EXPECT_TRUE(drive.torque_on());
  EXPECT_EQ(rig.run(0.5, 500), IoStatus::kOk) << rig.device->describe_fault();
}

TEST(CanReferenceRealDrive, ADriveWithoutMainsIsRefusedNamingTheDcLink) {
  Cia402Behaviour b;
  b.mains_on_at_start = false;
  Cia402Drive drive(b, damped_axis(), reference::monotonic_ns());
  ReferenceRig rig(slow_config({"device.can.cia402.dc_link_timeout_ms=700"}), drive);
  rig.device->configure();
  const std::string e = enable_error(rig);
  EXPECT_NE(e.find("the drive reports no DC-link voltage"), std::string::npos) << e;
  EXPECT_NE(e.find("after 700 ms"), std::string::npos) << e;
  EXPECT_FALSE(drive.torque_on());
  EXPECT_GT(drive.dc_link_refusals(), 1) << "the shutdown command written again while waiting";
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
