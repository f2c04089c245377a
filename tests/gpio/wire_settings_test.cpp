// The GPIO loopback wire format (every message round-trips; every malformed one is refused)
// and the device.gpio section (config/gpio.yaml loads; each wrong key is named with its line).
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "config/config_loader.h"
#include "drivers/gpio/gpio_settings.h"
#include "drivers/gpio/gpio_wire.h"
#include "gpio_example.h"

namespace hapticd::drivers::gpio {
namespace {

TEST(GpioWire, OutputRoundTripsAndRefusesWhatThePwmCoreWould) {
  std::array<std::uint8_t, wire::kOutputSize> buf{};
  const wire::Output o{12'345, 50'000, true, true, true};
  ASSERT_EQ(wire::encode_output(o, buf), wire::kOutputSize);
  wire::Output back;
  ASSERT_TRUE(wire::decode_output(buf, back));
  EXPECT_EQ(back.duty_ns, 12'345u);
  EXPECT_EQ(back.period_ns, 50'000u);
  EXPECT_TRUE(back.pwm_enabled && back.direction_level && back.inversed);
  wire::Output too_much{60'000, 50'000, true, false, false};
  wire::encode_output(too_much, buf);
  EXPECT_FALSE(wire::decode_output(buf, back)) << "duty above the period";
  wire::encode_output(o, buf);
  buf[1] |= 0x80;
  EXPECT_FALSE(wire::decode_output(buf, back)) << "unknown flag bits";
  EXPECT_FALSE(wire::decode_output(std::span(buf).first(wire::kOutputSize - 1), back));
  wire::encode_output(o, buf);
  buf[5] = 1;  // a reserved byte (found by fuzz/gpio_decoder_fuzzer.cpp)
  EXPECT_FALSE(wire::decode_output(buf, back)) << "reserved bytes must be zero";
  EXPECT_EQ(wire::encode_output(o, std::span(buf).first(3)), 0u) << "too small a buffer";
}

TEST(GpioWire, EdgesRoundTripAndEveryMalformedBatchIsRefused) {
  std::vector<Edge> edges;
  for (std::uint32_t i = 0; i < wire::kMaxEdgesPerMessage; ++i) {
    edges.push_back({1'000'000 + i, i + 7, static_cast<Line>(i % kLineCount), (i & 1u) != 0});
  }
  std::array<std::uint8_t, wire::kMaxMessageSize> buf{};
  const std::size_t n = wire::encode_edges(2'000'000, edges, buf);
  ASSERT_EQ(n, wire::kMaxMessageSize);
  const std::span<const std::uint8_t> msg(buf.data(), n);
  wire::EdgesHeader h;
  ASSERT_TRUE(wire::decode_edges_header(msg, h));
  EXPECT_EQ(h.count, wire::kMaxEdgesPerMessage);
  EXPECT_EQ(h.complete_until_ns, 2'000'000);
  for (std::size_t i = 0; i < h.count; ++i) {
    Edge e;
    ASSERT_TRUE(wire::decode_edge(msg, i, e));
    EXPECT_EQ(e.time_ns, edges[i].time_ns);
    EXPECT_EQ(e.seqno, edges[i].seqno);
    EXPECT_EQ(e.line, edges[i].line);
    EXPECT_EQ(e.level, edges[i].level);
  }
  Edge e;
  EXPECT_FALSE(wire::decode_edge(msg, h.count, e)) << "past the last edge";
  EXPECT_FALSE(wire::decode_edges_header(msg.first(n - 1), h)) << "cut short";
  std::vector<Edge> too_many(wire::kMaxEdgesPerMessage + 1);
  EXPECT_EQ(wire::encode_edges(0, too_many, buf), 0u);
  auto bad = buf;
  bad[wire::kEdgesHeaderSize + 12] = kLineCount;  // no such line
  EXPECT_FALSE(wire::decode_edge(std::span<const std::uint8_t>(bad.data(), n), 0, e));
  bad = buf;
  bad[wire::kEdgesHeaderSize + 13] = 2;  // a level is 0 or 1
  EXPECT_FALSE(wire::decode_edge(std::span<const std::uint8_t>(bad.data(), n), 0, e));
  bad = buf;
  bad[6] = 1;  // reserved
  EXPECT_FALSE(wire::decode_edges_header(std::span<const std::uint8_t>(bad.data(), n), h));
  bad = buf;
  bad[2] = 0xff;  // count above the maximum
  EXPECT_FALSE(wire::decode_edges_header(std::span<const std::uint8_t>(bad.data(), n), h));
  wire::Type t;
  EXPECT_FALSE(wire::peek_type({}, t));
  const std::uint8_t unknown[] = {9};
  EXPECT_FALSE(wire::peek_type(unknown, t));
}

TEST(GpioWire, HelloAndLevels) {
  std::array<std::uint8_t, wire::kLevelsSize> buf{};
  ASSERT_EQ(wire::encode_hello(buf), wire::kHelloSize);
  EXPECT_TRUE(wire::decode_hello(std::span(buf).first(1)));
  ASSERT_EQ(wire::encode_levels({wire::kLevelA | wire::kLevelFault, 42}, buf), wire::kLevelsSize);
  wire::Levels l;
  ASSERT_TRUE(wire::decode_levels(buf, l));
  EXPECT_EQ(l.levels, wire::kLevelA | wire::kLevelFault);
  EXPECT_EQ(l.time_ns, 42);
  buf[1] = 0x10;
  EXPECT_FALSE(wire::decode_levels(buf, l)) << "no such line";
}

std::string errors_of(const std::vector<std::string>& sets) {
  try {
    load_gpio_example(sets);
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const auto& m : e.messages()) all += m + "\n";
    return all;
  }
  return "";
}

TEST(GpioSettings, TheExampleLoads) {
  const config::Config cfg = load_gpio_example({});
  const GpioSettings& g = gpio_settings(cfg);
  ASSERT_EQ(g.joints.size(), 1u);
  EXPECT_FALSE(g.listed);
  const GpioJointSettings& s = g.joint(0);
  EXPECT_EQ(s.chip, "gpiochip0");
  EXPECT_EQ(s.line_a, 0u);
  EXPECT_EQ(s.line_b, 1u);
  EXPECT_EQ(s.line_direction, 2u);
  ASSERT_TRUE(s.line_fault.has_value());
  EXPECT_FALSE(s.line_index.has_value());
  EXPECT_EQ(s.counts_per_unit, 100000.0);
  EXPECT_EQ(s.start_count, -2000);
  EXPECT_EQ(g.pwm_period_ns, 50'000u);
  EXPECT_EQ(wiring::find_driver("gpio").declared_delay(cfg), 0);
}

TEST(GpioSettings, EveryWrongKeyIsNamedWithItsPlace) {
  EXPECT_NE(errors_of({"device.gpio.lines.b=0"}).find("device.gpio.lines.b: line 0 is used twice"),
            std::string::npos);
  EXPECT_NE(errors_of({"device.gpio.counts_per_unit=0"}).find("must not be 0"), std::string::npos);
  EXPECT_NE(errors_of({"device.gpio.index_count=5"}).find("needs lines.index"), std::string::npos);
  EXPECT_NE(errors_of({"device.gpio.pwm.polarity=backwards"}).find("device.gpio.pwm.polarity"),
            std::string::npos);
  EXPECT_NE(errors_of({"device.gpio.pwm.period_ns=0"}).find("device.gpio.pwm.period_ns"),
            std::string::npos);
  EXPECT_NE(errors_of({"device.gpio.pwm.sysfs_root=sys/class/pwm"}).find("absolute path"),
            std::string::npos);
  EXPECT_NE(
      errors_of({"device.gpio.lines={a: 0, b: 1}"}).find("device.gpio.lines.direction: missing"),
      std::string::npos);
  // Issue 22: the old stop modes. Neither can be honoured through a PWM channel (a disabled
  // one's output is undefined), so the key is refused with why, not silently dropped.
  for (const char* mode : {"coast", "brake"}) {
    const std::string e = errors_of({std::string("device.gpio.on_disable=") + mode});
    EXPECT_NE(e.find("device.gpio.on_disable: is no longer a setting"), std::string::npos) << e;
    EXPECT_NE(e.find("duty 0 on the enabled PWM channel"), std::string::npos) << e;
  }
  EXPECT_NE(errors_of({"device.gpio.max_edge_rate=-1"}).find("device.gpio.max_edge_rate"),
            std::string::npos);
  const std::string unknown = errors_of({"device.gpio.chp=x"});
  EXPECT_NE(unknown.find("device.gpio.chp: unknown key (did you mean 'chip'?)"), std::string::npos)
      << unknown;
  // A file error carries the file and line of the key.
  std::string text = gpio_example();
  text.replace(text.find("max_edge_rate: 200000"), 21, "max_edge_rate: fast  ");
  try {
    config::load_config_text(text, "gpio.yaml", {}, HAPTICD_SOURCE_DIR "/config",
                             wiring::driver_schemas());
    FAIL() << "accepted a word for a number";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(e.messages().front().find("gpio.yaml:"), std::string::npos);
    EXPECT_NE(e.messages().front().find("device.gpio.max_edge_rate"), std::string::npos);
  }
}

TEST(GpioSettings, DeclaredDelayFollowsThePwmPeriod) {
  GpioSettings s;
  const double t = 1e-3;
  for (const auto& [period, delay] : std::vector<std::pair<std::uint64_t, int>>{{50'000, 0},
                                                                                {1'000'000, 0},
                                                                                {1'000'001, 1},
                                                                                {1'500'000, 1},
                                                                                {2'000'000, 1},
                                                                                {2'500'000, 2}}) {
    s.pwm_period_ns = period;
    EXPECT_EQ(declared_delay_samples(s, t), delay) << period << " ns";
  }
  // `check` analyses it: a slow PWM adds its delay to the gate's loop.
  const config::Config cfg = load_gpio_example({"device.gpio.pwm.period_ns=2500000"});
  EXPECT_EQ(wiring::find_driver("gpio").declared_delay(cfg), 2);
}

}  // namespace
}  // namespace hapticd::drivers::gpio
