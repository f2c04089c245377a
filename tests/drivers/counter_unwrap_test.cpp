// drivers/io/counter_unwrap.h: a counter narrower than the loop's position followed across its
// rollover in both directions, for any width, signed or not; the first sample sets the base.
#include "drivers/io/counter_unwrap.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

namespace hapticd::io {
namespace {

constexpr std::int64_t kMax32 = std::numeric_limits<std::int32_t>::max();

// A signed 32-bit count as a drive sends it: the low 32 bits of the true count.
std::uint64_t raw32(std::int64_t count) { return static_cast<std::uint32_t>(count); }

TEST(CounterUnwrap, TheFirstSampleIsTheRawValueSignExtended) {
  CounterUnwrap u(32, true);
  EXPECT_FALSE(u.started());
  EXPECT_EQ(u.next(raw32(-5)), -5);
  EXPECT_TRUE(u.started());
  CounterUnwrap v(32, true);
  EXPECT_EQ(v.next(static_cast<std::uint64_t>(std::int64_t{-5})), -5) << "sign-extended input too";
  CounterUnwrap w(16, false);
  EXPECT_EQ(w.next(0xFFFB), 0xFFFB) << "an unsigned counter starts where it is";
}

TEST(CounterUnwrap, A32BitPositionCrossesTheWrapBothWays) {
  CounterUnwrap u(32, true);
  std::int64_t truth = kMax32 - 300;
  u.next(raw32(truth));
  for (int i = 0; i < 100; ++i) {  // up through +2^31 and on
    truth += 7;
    ASSERT_EQ(u.next(raw32(truth)), truth) << i;
  }
  EXPECT_GT(u.value(), kMax32);
  for (int i = 0; i < 200; ++i) {  // back down through it
    truth -= 5;
    ASSERT_EQ(u.next(raw32(truth)), truth) << i;
  }
  EXPECT_LT(u.value(), kMax32);
}

TEST(CounterUnwrap, TheNegativeEndWrapsToo) {
  CounterUnwrap u(32, true);
  std::int64_t truth = -kMax32 + 10;  // near -2^31
  u.next(raw32(truth));
  for (const std::int64_t step : {-20, -1000, 3000, -5000, 2'000'000'000, -2'000'000'000}) {
    truth += step;
    ASSERT_EQ(u.next(raw32(truth)), truth) << step;
  }
}

TEST(CounterUnwrap, AStepOfHalfTheRangeOrMoreIsTakenTheShortWay) {
  CounterUnwrap u(8, false);
  u.next(0);
  EXPECT_EQ(u.next(127), 127);
  EXPECT_EQ(u.next(255), 127 + (255 - 127 - 256)) << "+128 is -128 modulo 256";
  EXPECT_EQ(u.difference(128, 0), -128);
  EXPECT_EQ(u.difference(127, 0), 127);
}

TEST(CounterUnwrap, AnyWidth) {
  for (const int bits : {1, 2, 12, 16, 24, 31, 32, 33, 48, 63, 64}) {
    SCOPED_TRACE(bits);
    CounterUnwrap u(bits, true);
    const std::int64_t step = bits == 1 ? 0 : bits == 2 ? 1 : 3;
    std::int64_t truth = 0;
    u.next(0);
    // Several times round the counter's whole range (for narrow ones), each step below half.
    for (int i = 0; i < 600; ++i) {
      truth += step;
      ASSERT_EQ(u.next(static_cast<std::uint64_t>(truth)), truth) << i;
    }
    EXPECT_EQ(u.difference(0, 0), 0);
  }
}

TEST(CounterUnwrap, A64BitCounterTakesTheHalfwayStepWithoutOverflow) {
  CounterUnwrap u(64, true);
  EXPECT_EQ(u.difference(std::uint64_t{1} << 63, 0), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(u.next(~std::uint64_t{0}), -1);
  EXPECT_EQ(u.next(1), 1);
}

TEST(CounterUnwrap, ResetMakesTheNextSampleTheBaseAgain) {
  CounterUnwrap u(32, true);
  u.next(raw32(kMax32));
  EXPECT_EQ(u.next(raw32(kMax32 + 2)), kMax32 + 2);
  u.reset();
  EXPECT_EQ(u.next(raw32(kMax32 + 2)), -kMax32 + 0) << "-2^31 + 1: the raw value, as a new session";
}

}  // namespace
}  // namespace hapticd::io
