// Hex as users read it in fault texts, listings and udev rules: "0x", zero-padded to the width
// asked, never cut short, upper case unless lower is asked for.
#include <gtest/gtest.h>

#include <cstdint>

#include "base/hex.h"

namespace hapticd::base {
namespace {

TEST(Hex, PadsToTheWidthAsked) {
  EXPECT_EQ(hex(0x701, 3), "0x701");
  EXPECT_EQ(hex(0x21, 3), "0x021");
  EXPECT_EQ(hex(0xFF, 8), "0x000000FF");
  EXPECT_EQ(hex(0, 2), "0x00");
  EXPECT_EQ(hex(0), "0x0");
}

TEST(Hex, NeverCutsAValueShort) {
  EXPECT_EQ(hex(0x12345, 2), "0x12345");
  EXPECT_EQ(hex(UINT64_MAX), "0xFFFFFFFFFFFFFFFF");
}

TEST(Hex, LowerCaseForUsbIds) {
  EXPECT_EQ(hex(0xffb0, 4, HexCase::kLower), "0xffb0");
  EXPECT_EQ(hex(0x46d, 4, HexCase::kLower).substr(2), "046d");
  EXPECT_EQ(hex(0xABCDEF, 1), "0xABCDEF");
}

}  // namespace
}  // namespace hapticd::base
