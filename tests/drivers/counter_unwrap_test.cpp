// drivers/io/counter_unwrap.h: a counter narrower than the position, followed across its wrap.
#include "drivers/io/counter_unwrap.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace hapticd::io {
namespace {

TEST(CounterUnwrap, TheStepIsTheShortWayRound) {
  EXPECT_EQ(wrapped_step(65535, 0, 16), 1);
  EXPECT_EQ(wrapped_step(0, 65535, 16), -1);
  EXPECT_EQ(wrapped_step(32767, -32768, 16), 1) << "an i16 over its top";
  EXPECT_EQ(wrapped_step(-32768, 32767, 16), -1);
  EXPECT_EQ(wrapped_step(100, 300, 16), 200);
  EXPECT_EQ(wrapped_step(0, 32768, 16), -32768) << "half the range: taken as backwards";
  EXPECT_EQ(wrapped_step(0, 32767, 16), 32767);
  EXPECT_EQ(wrapped_step(0x7FFFFFFF, -0x7FFFFFFF - 1, 32), 1) << "CiA 402's i32 position";
  EXPECT_EQ(wrapped_step(4095, 0, 12), 1);
  EXPECT_EQ(wrapped_step(1, 0, 1), -1);
}

TEST(CounterUnwrap, AnAxisTurningPastTheFieldsEndsKeepsCounting) {
  CounterUnwrap u(16);
  EXPECT_EQ(u.update(-32000), -32000) << "the first reading as it is";
  std::int64_t raw = -32000, real = -32000;
  for (int i = 0; i < 2000; ++i) {  // three turns of an i16 backwards, 100 counts a sample
    real -= 100;
    raw = static_cast<std::int16_t>(static_cast<std::uint16_t>(real));
    ASSERT_EQ(u.update(raw), real) << "sample " << i;
  }
  for (int i = 0; i < 4000; ++i) {
    real += 77;
    raw = static_cast<std::int16_t>(static_cast<std::uint16_t>(real));
    ASSERT_EQ(u.update(raw), real) << "sample " << i;
  }
  u.reset();
  EXPECT_EQ(u.update(5), 5) << "after a reset the reading is taken as it is again";
  EXPECT_EQ(u.count(), 5);
}

TEST(CounterUnwrap, UnsignedReadingsOfAnyWidth) {
  CounterUnwrap u(12);
  EXPECT_EQ(u.update(4000), 4000);
  EXPECT_EQ(u.update(50), 4146);  // 4000 -> 4095 -> 0 -> 50
  EXPECT_EQ(u.update(4090), 4090) << "and back the short way";
}

}  // namespace
}  // namespace hapticd::io
