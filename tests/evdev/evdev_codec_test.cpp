// The evdev driver's pure codecs: the loopback framing both ends speak, the axis and force
// arithmetic, and the delay each kernel FF driver class is declared with.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_wire.h"

namespace hapticd::drivers::evdev {
namespace {

TEST(EvdevWire, EveryMessageComesBackAsItWasSent) {
  wire::Message m;
  m.type = wire::Type::kFacts;
  m.facts.name = "Logitech WingMan";
  m.facts.uniq = "0042";
  m.facts.vendor = 0x046d;
  m.facts.range = {-32767, 32767, 12};
  m.facts.value = -5;
  m.facts.fuzz = 255;
  m.facts.has_axis = m.facts.ff_constant = m.facts.ff_autocenter = true;
  m.facts.ff_effects = 16;
  std::vector<std::uint8_t> bytes;
  wire::encode(m, bytes);
  const auto back = wire::decode(bytes);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->facts.name, "Logitech WingMan");
  EXPECT_EQ(back->facts.uniq, "0042");
  EXPECT_EQ(back->facts.range.minimum, -32767);
  EXPECT_EQ(back->facts.fuzz, 255);
  EXPECT_TRUE(back->facts.ff_autocenter);
  EXPECT_FALSE(back->facts.ff_gain);

  std::array<std::uint8_t, 32> buf{};
  const std::size_t n = wire::encode_upload({3, 0xC000, -1234, 0}, buf);
  const auto up = wire::decode({buf.data(), n});
  ASSERT_TRUE(up);
  EXPECT_EQ(up->type, wire::Type::kUpload);
  EXPECT_EQ(up->effect.id, 3);
  EXPECT_EQ(up->effect.level, -1234);
  EXPECT_EQ(up->effect.direction, 0xC000);
  const std::size_t e = wire::encode_event({kEvAbs, 0x08, -7, 123456789012}, buf);
  const auto ev = wire::decode({buf.data(), e});
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->event.value, -7);
  EXPECT_EQ(ev->event.time_ns, 123456789012);
  wire::Message answers;  // the type alone: its descriptor travels beside the bytes
  answers.type = wire::Type::kAnswers;
  wire::encode(answers, bytes);
  EXPECT_EQ(bytes, std::vector<std::uint8_t>{9});
  const auto a = wire::decode(bytes);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->type, wire::Type::kAnswers);
  const std::uint8_t answers_with_more[] = {9, 0};
  EXPECT_FALSE(wire::decode(answers_with_more));
}

TEST(EvdevWire, BytesThatAreNoMessageAreRefused) {
  EXPECT_FALSE(wire::decode({}));
  const std::uint8_t unknown[] = {99, 0, 0};
  EXPECT_FALSE(wire::decode(unknown));
  const std::uint8_t short_event[] = {1, 3, 0};
  EXPECT_FALSE(wire::decode(short_event));
  // A string that claims more bytes than there are.
  wire::Message m;
  m.type = wire::Type::kFacts;
  std::vector<std::uint8_t> bytes;
  wire::encode(m, bytes);
  bytes[bytes.size() - 3] = 200;
  EXPECT_FALSE(wire::decode(bytes));
}

TEST(EvdevArithmetic, LevelsAxisAndDirection) {
  EXPECT_EQ(force_level(10.0, 10.0), 0x7fff);
  EXPECT_EQ(force_level(-20.0, 10.0), -0x7fff) << "held within the level's range";
  EXPECT_EQ(force_level(5.0, 10.0), 16384);
  EXPECT_EQ(force_level(std::nan(""), 10.0), 0);
  EXPECT_NEAR(level_force(16384, 10.0), 5.0, 1e-3);
  const AxisSettings range{0, Scale::kRange, -1.0, 1.0, false, 0.0};
  EXPECT_DOUBLE_EQ(axis_position(0, range, {0, 1000, 0}), -1.0);
  EXPECT_DOUBLE_EQ(axis_position(500, range, {0, 1000, 0}), 0.0);
  const AxisSettings per_mm{0, Scale::kResolution, 0, 0, false, 0.002};
  EXPECT_DOUBLE_EQ(axis_position(100, per_mm, {0, 0, 10}), 0.012) << "10 units/mm, + 2 mm";
  const AxisSettings per_rad{0, Scale::kResolution, 0, 0, true, 0.0};
  EXPECT_DOUBLE_EQ(axis_position(300, per_rad, {0, 0, 100}), 3.0);
  EXPECT_EQ(direction_of(90), 0x4000);
  EXPECT_EQ(direction_of(270), 0xC000);
  EXPECT_EQ(abs_code("ABS_WHEEL"), 0x08);
  EXPECT_FALSE(abs_code("ABS_MT_SLOT"));
  EXPECT_EQ(abs_name(0x3e), "ABS_0x3e");
}

// docs/drivers/evdev.md, "Delay": the samples each class declares at a few rates.
TEST(EvdevDelay, EachDriverClassDeclaresItsOwn) {
  EvdevSettings s;
  s.ff_driver = FfDriver::kUinput;
  EXPECT_EQ(declared_delay_samples(s, 1e-3), 0);
  EXPECT_EQ(highest_rate_hz(s), 0.0) << "no bound of the kernel's";
  s.ff_driver = FfDriver::kPidff;
  EXPECT_EQ(declared_delay_samples(s, 1e-3), 1) << "like the HID driver at 1 kHz, 1 ms polling";
  EXPECT_EQ(declared_delay_samples(s, 4e-3), 0);
  s.ff_driver = FfDriver::kMemless;
  EXPECT_EQ(declared_delay_samples(s, 4e-3), 1) << "2 ms of USB and a 4 ms jiffy at 250 Hz";
  EXPECT_EQ(declared_delay_samples(s, 1e-2), 0);
  EXPECT_EQ(highest_rate_hz(s), 250.0);
  s.poll_interval_ms = 10;  // a wheel polled every 10 ms
  EXPECT_EQ(highest_rate_hz(s), 100.0);
  EXPECT_EQ(declared_delay_samples(s, 1e-2), 2);
}

// docs/drivers/evdev.md, "The update thread": what the update's own time L adds, ceil(2L/T) - 1
// (none while L <= T/2), on top of each class's, and the longest update that covers.
TEST(EvdevDelay, TheUpdatesOwnTimeIsDeclaredAndCovered) {
  EvdevSettings s;
  s.ff_driver = FfDriver::kUinput;
  EXPECT_DOUBLE_EQ(covered_update_s(s, 1e-2), 5e-3) << "half a period with L = 0";
  s.update_latency_ms = 5;
  EXPECT_EQ(declared_delay_samples(s, 1e-2), 0) << "L = T/2: within the tick";
  s.update_latency_ms = 15;  // issue 34's device at 100 Hz
  EXPECT_EQ(declared_delay_samples(s, 1e-2), 2);
  EXPECT_DOUBLE_EQ(covered_update_s(s, 1e-2), 15e-3);
  s.update_latency_ms = 25;
  EXPECT_EQ(declared_delay_samples(s, 1e-2), 4);
  EXPECT_DOUBLE_EQ(covered_update_s(s, 1e-2), 25e-3);
  s.update_latency_ms = 16;  // covered up to the next whole sample's worth
  EXPECT_EQ(declared_delay_samples(s, 1e-2), 3);
  EXPECT_DOUBLE_EQ(covered_update_s(s, 1e-2), 20e-3);
  s.ff_driver = FfDriver::kPidff;  // 1 for the USB link at 1 kHz, then the update's own
  s.update_latency_ms = 0;
  EXPECT_EQ(declared_delay_samples(s, 1e-3), 1);
  EXPECT_DOUBLE_EQ(covered_update_s(s, 1e-3), 0.5e-3);
  s.update_latency_ms = 2;
  EXPECT_EQ(declared_delay_samples(s, 1e-3), 1 + 3);
}

}  // namespace
}  // namespace hapticd::drivers::evdev
