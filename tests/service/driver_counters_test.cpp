// Issue 24: a driver's health shows wherever the loop's does. For each driver of this build,
// a loopback run's `hapticctl status` and its summary (JSON and text) list the driver's own
// counters beside the loop's, under the driver's name, with its ordinary traffic counted.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "daemon.h"
#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

struct DriverCase {
  const char* config;   // config/<config>
  const char* driver;   // its counters' source
  const char* counter;  // one of its counters
  bool counts_traffic;  // that counter grows in an ordinary run
  // A --set of its own, or null: what a loaded host does to this driver is not the subject.
  const char* set = nullptr;
};

std::vector<DriverCase> cases() {
  std::vector<DriverCase> c;
#if HAPTICD_TEST_WITH_HID
  c.push_back({"hid-report.yaml", "hid", "input_reports", true});
  c.push_back({"hid-pid.yaml", "hid", "input_reports", true});
#endif
#if HAPTICD_TEST_WITH_GPIO
  c.push_back({"gpio.yaml", "gpio", "missed_edges", false});
#endif
#if HAPTICD_TEST_WITH_CAN
  c.push_back({"can-cia402.yaml", "can", "frames_received", true});
  c.push_back({"can-odrive.yaml", "can", "frames_received", true});
#endif
#if HAPTICD_TEST_WITH_EVDEV
  // The emulated uinput answers each update on a thread the sanitizer builds and a loaded host
  // slow: its late updates are counted (late_updates), not a fault to this test.
  c.push_back({"evdev.yaml", "evdev", "axis_events", true, "device.evdev.late_update_fault=10000"});
#endif
  return c;
}

void PrintTo(const DriverCase& c, std::ostream* os) { *os << c.config; }

std::string name(const ::testing::TestParamInfo<DriverCase>& info) {
  std::string n = info.param.config;
  for (char& ch : n) {
    if (ch == '-' || ch == '.') ch = '_';
  }
  return n;
}

class DriverCounters : public ::testing::TestWithParam<DriverCase> {};

TEST_P(DriverCounters, StatusAndSummaryListTheDriversCountersBesideTheLoops) {
  const DriverCase& c = GetParam();
  std::vector<std::string> args{"--loopback", "--config", source_dir() + "/config/" + c.config,
                                "--duration", "30"};
  if (c.set != nullptr) args.insert(args.end(), {"--set", c.set});
  Daemon d(args);
  ASSERT_TRUE(d.ready()) << d.wait().err;  // what ended it before it was ready
  const json s = d.wait_status([&](const json& j) {
    if (!j.contains("counters") || !j["counters"].contains(c.driver)) return false;
    const json& v = j["counters"][c.driver][c.counter];
    return v.is_number() && (!c.counts_traffic || v.get<std::uint64_t>() > 50);
  });
  ASSERT_TRUE(s["counters"].contains(c.driver)) << s.dump(2);
  ASSERT_TRUE(s["counters"][c.driver].contains(c.counter)) << s["counters"].dump(2);
  if (c.counts_traffic) {
    EXPECT_GT(s["counters"][c.driver][c.counter].get<std::uint64_t>(), 50u);
  }
  EXPECT_TRUE(s["counters"]["loop"].contains("stale_ticks")) << s["counters"].dump(2);
  EXPECT_TRUE(s["anomalies"].is_array());
  const ProcessResult text = d.ctl({"status"});
  EXPECT_NE(text.out.find(std::string("  ") + c.driver), std::string::npos) << text.out;
  EXPECT_NE(text.out.find(c.counter), std::string::npos) << text.out;

  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  const ProcessResult end = d.wait();
  ASSERT_EQ(end.exit_code, 0) << end.err;
  const json summary = json::parse(read_file(d.summary()));
  ASSERT_TRUE(summary["counters"][c.driver].contains(c.counter)) << summary["counters"].dump(2);
  EXPECT_GE(summary["counters"][c.driver][c.counter], s["counters"][c.driver][c.counter]);
  EXPECT_NE(end.out.find(std::string("  ") + c.driver), std::string::npos) << end.out;
  EXPECT_NE(end.out.find("anomalies"), std::string::npos) << end.out;
}

INSTANTIATE_TEST_SUITE_P(Drivers, DriverCounters, ::testing::ValuesIn(cases()), name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(DriverCounters);

}  // namespace
}  // namespace hapticd::testing
