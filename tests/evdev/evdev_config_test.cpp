// device.evdev as a person writes it: the example loads, and every mistake is reported at its
// line with the key that must change.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "config/config_loader.h"
#include "drivers/evdev/evdev_settings.h"
#include "wiring/registry.h"

namespace hapticd::drivers::evdev {
namespace {

std::string example() {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/evdev.yaml");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

config::Config load(std::vector<std::string> sets = {}) {
  std::vector<config::Override> o;
  for (const std::string& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(example(), "evdev.yaml", o, ".", wiring::driver_schemas());
}

std::string errors(std::vector<std::string> sets) {
  try {
    load(std::move(sets));
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const std::string& m : e.messages()) all += m + "\n";
    return all;
  }
  return "(loaded)";
}

TEST(EvdevConfig, TheExampleLoads) {
  const config::Config c = load();
  const EvdevSettings& s = evdev_settings(c);
  EXPECT_EQ(s.select.vendor_id, 0x1209);
  EXPECT_EQ(s.axis.code, 0);
  EXPECT_EQ(s.ff_driver, FfDriver::kPidff);
  EXPECT_EQ(s.liveness_ms, 0.0);
  EXPECT_EQ(s.update_latency_ms, 0.0);
  EXPECT_EQ(s.late_update_fault, 10);
  EXPECT_FALSE(s.axis.wraps);
  EXPECT_EQ(s.writer_priority, 79) << "one below loop.rt_priority 80";
  EXPECT_EQ(wiring::find_driver("evdev").declared_delay(c), 1);
  const config::Config slow = load({"device.evdev.update_latency_ms=2"});
  EXPECT_EQ(wiring::find_driver("evdev").declared_delay(slow), 1 + 3)
      << "the USB link's, and ceil(2 x 2 ms / 1 ms) - 1 for the update's own";
}

TEST(EvdevConfig, AMistakeInTheFileIsNamedAtItsLine) {
  std::string text = example();
  const std::size_t at = text.find("code: ABS_X");
  ASSERT_NE(at, std::string::npos);
  const long line = std::count(text.begin(), text.begin() + static_cast<long>(at), '\n') + 1;
  text.replace(at, 11, "code: 0x40");
  try {
    config::load_config_text(text, "evdev.yaml", {}, ".", wiring::driver_schemas());
    ADD_FAILURE() << "loaded";
  } catch (const config::ConfigError& e) {
    ASSERT_FALSE(e.messages().empty());
    EXPECT_EQ(e.messages()[0], "evdev.yaml:" + std::to_string(line) +
                                   ": device.evdev.axis.code: must be an integer in 0..63 (0x3F), "
                                   "decimal or 0x hexadecimal, got '0x40'");
  }
}

TEST(EvdevConfig, MistakesAreNamedWithTheKey) {
  EXPECT_NE(errors({"device.evdev.axis.code=ABS_WHEELS"})
                .find("--set device.evdev.axis.code=ABS_WHEELS: device.evdev.axis.code: must be an "
                      "absolute axis (ABS_X"),
            std::string::npos)
      << errors({"device.evdev.axis.code=ABS_WHEELS"});
  EXPECT_NE(errors({"device.evdev.force_full_scale=5"}).find("cannot represent device.max_force"),
            std::string::npos);
  EXPECT_NE(
      errors({"device.evdev.ff_driver=memless"})
          .find("memless passes at most 250 updates a second to the device (one per kernel timer "
                "tick, kernel_hz): loop.rate_hz 1000 is above it"),
      std::string::npos)
      << errors({"device.evdev.ff_driver=memless"});
  EXPECT_NE(errors({"device.evdev.ff_driver=uinput"})
                .find("device.evdev.poll_interval_ms: not used by ff_driver uinput"),
            std::string::npos);
  EXPECT_EQ(errors({"device.evdev.ff_driver=uinput", "device.evdev.poll_interval_ms="}), "(loaded)")
      << "an example's key removed from the command line";
  EXPECT_NE(errors({"device.evdev.kernel_hz=300"}).find("only with ff_driver: memless"),
            std::string::npos);
  EXPECT_NE(errors({"device.evdev.liveness_ms=1"}).find("at least two sample periods"),
            std::string::npos);
  EXPECT_NE(errors({"device.evdev.select={path: /tmp/x}"}).find("under /dev/input/"),
            std::string::npos);
  EXPECT_NE(errors({"device.evdev.select={}"}).find("selects every input device"),
            std::string::npos);
  EXPECT_NE(
      errors({"device.evdev.axis={code: ABS_X, min: 1, max: 1}"}).find("min and max must differ"),
      std::string::npos);
  // Each finite, their span not: every position would be NaN (0 * inf at the axis' minimum).
  EXPECT_NE(errors({"device.evdev.axis={code: ABS_X, min: -1e308, max: 1e308}"})
                .find("device.evdev.axis.max: max - min must be a finite number"),
            std::string::npos)
      << errors({"device.evdev.axis={code: ABS_X, min: -1e308, max: 1e308}"});
  EXPECT_NE(errors({"device.evdev.axis={code: ABS_X, min: 0, max: 1, rotary: true}"})
                .find("device.evdev.axis.rotary: only with scale: resolution"),
            std::string::npos);
  EXPECT_NE(errors({"device.evdev.update_latency_ms=-1"})
                .find("device.evdev.update_latency_ms: must be in [0, 10000], got '-1'"),
            std::string::npos)
      << errors({"device.evdev.update_latency_ms=-1"});
  EXPECT_NE(errors({"device.evdev.late_update_fault=0"})
                .find("device.evdev.late_update_fault: must be in 1..10000"),
            std::string::npos);
  EXPECT_NE(errors({"device.evdev.axis={code: ABS_X, min: 0, max: 1, wraps: yes please}"})
                .find("device.evdev.axis.wraps: must be true or false"),
            std::string::npos);
  EXPECT_NE(errors({"device.evdev.gian=0.5"})
                .find("device.evdev.gian: unknown key (did you mean 'gain'?)"),
            std::string::npos)
      << errors({"device.evdev.gian=0.5"});
}

// The simulated device is an input device: its axis holds 32-bit values, so an encoder too fine
// for its travel is refused, naming the key, where it would have wrapped to a wrong position.
TEST(EvdevConfig, ASimulatedEncoderTooFineForAnInputAxisIsRefusedNamingTheKey) {
  const config::Config fine = load({"device.sim.counts_per_unit=1e11"});  // 1e10 counts
  try {
    wiring::find_driver("evdev").make_loopback(fine);
    ADD_FAILURE() << "a simulated axis of 1e10 counts was made";
  } catch (const config::ConfigError& e) {
    ASSERT_EQ(e.messages().size(), 1u);
    EXPECT_EQ(e.messages()[0].find("--set device.sim.counts_per_unit=1e11: "
                                   "device.sim.counts_per_unit: the simulated input device would "
                                   "have 1e+10 counts over its travel"),
              0u)
        << e.messages()[0];
  }
  EXPECT_NO_THROW(
      wiring::find_driver("evdev").make_loopback(load({"device.sim.counts_per_unit=2e10"})))
      << "2e9 counts fit";
}

}  // namespace
}  // namespace hapticd::drivers::evdev
