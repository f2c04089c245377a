// hapticd's report profile against the reference Switch-Pro-style device (switch_pro_style.h)
// on uhid, in the kernel test machine, through hidraw: config/hid-report.yaml with the input
// layout of the Pro Controller's report 0x30, the position the left stick's X, 12 bits at data
// byte 5 sharing byte 6 with Y. At 50 Hz, as the other vendor devices' tests (a loaded emulator
// stalls hapticd for 100 ms and more), with safety.max_speed 1 m/s: ten times what the hand
// makes the axis do, and far below the jump of a Y nibble read into X.
#include <gtest/gtest.h>

#include <iostream>

#include "hapticd_process.h"
#include "switch_pro_style.h"

namespace hapticd::reference {
namespace {

constexpr double kStiffness = 150.0;  // N/m
constexpr double kPush = 1.0;         // N

std::vector<std::string> sets(const std::string& serial, const std::string& position) {
  return {"loop.rate_hz=50", "loop.overrun_fault_streak=1000",
          "wall.stiffness=" + std::to_string(kStiffness), "safety.stale_fault_ticks=50",
          // The emulated machine's USB: the push's motion up to 300 ms late, and the push
          // long enough that a late zero after it changes it little.
          "safety.direction_check.max_latency_ms=300", "safety.direction_check.duration_ms=100",
          "safety.max_speed=1", "device.hid.select.product_id=0x0003",
          "device.hid.select.serial=" + serial,
          "device.hid.report.input={report_id: 0x30, length: 48, position: " + position + "}"};
}

// X: 12 bits from bit 0 of byte 5; 2048 counts of 20 um at the wall.
const std::string kPacked = "{byte: 5, bits: 12, scale: 2.0e-5, offset: -0.04096}";

// Issue 34 item 5: at rest in the wall, F/K within 2 %.
TEST(SwitchProStyle, ATwelveBitPackedPositionRendersTheWall) {
  SwitchProStyleOptions o;
  o.serial = "switch-pro-packed";
  SwitchProStyle d(o);
  double rest = 0.0;
  const HapticdRun r = run_hapticd(
      shipped("hid-report.yaml"), sets(o.serial, kPacked), {"--duration", "8"}, [&](pid_t) {
        ASSERT_TRUE(wait_until([&] { return d.output_on(); })) << "never enabled";
        ASSERT_TRUE(wait_armed()) << "the direction check never armed the wall";
        d.axis().hand(kPush, 5.0);
        std::this_thread::sleep_for(std::chrono::seconds(4));
        rest = d.axis().position();
      });
  ASSERT_EQ(r.status, 0) << r.faults() << "\n" << r.log;
  EXPECT_EQ(r.faults(), "[]");
  EXPECT_NEAR(rest, kPush / kStiffness, 0.02 * kPush / kStiffness) << "resting penetration";
  EXPECT_GT(r.summary["counters"]["loop"]["contact_ticks"].get<std::uint64_t>(), 100u);
  std::cout << "12-bit stick X: resting penetration " << rest << " m (F/K " << kPush / kStiffness
            << "), " << d.reports() << " reports\n";
}

// The nearest whole-byte layout, u16 at byte 5, takes Y's low nibble into the position: it
// jumps by 4096 counts (82 mm) as the resting stick's Y moves a count, and the run ends on the
// speed check with zero commanded.
TEST(SwitchProStyle, AWholeByteLayoutReadsTheNeighboursNibbleAndFaultsSafely) {
  SwitchProStyleOptions o;
  o.serial = "switch-pro-u16";
  SwitchProStyle d(o);
  const HapticdRun r = run_hapticd(
      shipped("hid-report.yaml"),
      sets(o.serial, "{byte: 5, type: u16, scale: 2.0e-5, offset: -0.04096}"), {"--duration", "8"});
  EXPECT_EQ(r.status, 1) << r.log;
  EXPECT_NE(r.faults().find("impossible encoder data"), std::string::npos) << r.faults();
  EXPECT_EQ(r.summary["device"].value("final_command", -1.0), 0.0);
}

}  // namespace
}  // namespace hapticd::reference
