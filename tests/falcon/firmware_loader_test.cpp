// The firmware load's steps, its bounded tries and what each try records (docs/drivers/
// falcon.md), against the simulated bootloader of fake_falcon_link.h.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "drivers/falcon/firmware_loader.h"
#include "fake_falcon_link.h"
#include "falcon_image.h"

namespace hapticd::drivers::falcon::testing {
namespace {

using hapticd::testing::falcon_image_bytes;

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(FalconLoad, ABootloaderThatIgnoresTheFirstTryLoadsOnTheSecond) {
  FakeFalconLink link;
  link.ignore_first_pulses = 1;
  const auto image = falcon_image_bytes();
  const LoadResult r = load_firmware(link, image, 3, kFast);
  ASSERT_TRUE(r.loaded) << describe(r);
  ASSERT_EQ(r.tries.size(), 2u);
  EXPECT_TRUE(contains(r.tries[0].failed_at, "first check")) << r.tries[0].failed_at;
  EXPECT_EQ(r.tries[0].saw, "nothing");
  EXPECT_EQ(describe(r).substr(describe(r).size() - 13), "try 2: loaded");
  EXPECT_EQ(link.image, image) << "the whole image, once, on the try that loaded";
  EXPECT_EQ(link.pulses, 2) << "each try resets the microcontroller into its bootloader";
  EXPECT_EQ(link.divisor, 2) << "the firmware's rate";
  EXPECT_EQ(link.latency_ms, 1);
  EXPECT_GE(link.packets_answered, 1);
}

TEST(FalconLoad, TheTriesAreBoundedAndEachSaysWhereItFailed) {
  FakeFalconLink link;
  link.ignore_first_pulses = 100;
  const LoadResult r = load_firmware(link, falcon_image_bytes(), 4, kFast);
  EXPECT_FALSE(r.loaded);
  ASSERT_EQ(r.tries.size(), 4u);
  EXPECT_EQ(link.pulses, 4);
  for (const LoadTry& t : r.tries) EXPECT_TRUE(contains(t.failed_at, "0a 44 2c 0d"));
}

TEST(FalconLoad, AWrongEchoFailsTheTryAtItsChunkWithTheBytesSeen) {
  FakeFalconLink link;
  link.corrupt_echo_at = 300;  // in the third chunk, from byte 256
  const LoadResult r = load_firmware(link, falcon_image_bytes(), 2, kFast);
  EXPECT_FALSE(r.loaded);
  ASSERT_EQ(r.tries.size(), 2u);
  EXPECT_TRUE(contains(r.tries[1].failed_at, "the image's echo at byte 256")) << describe(r);
  EXPECT_EQ(link.divisor, 0x15) << "never switched to the firmware's rate";
  EXPECT_NE(r.tries[1].saw, "nothing");
}

TEST(FalconLoad, AFirmwareThatNeverAnswersIsNamed) {
  FakeFalconLink link;
  link.silent_firmware = true;
  const LoadResult r = load_firmware(link, falcon_image_bytes(), 2, kFast);
  EXPECT_FALSE(r.loaded);
  EXPECT_TRUE(contains(describe(r), "try 2: the firmware never answered a packet (3 sent)"))
      << describe(r);
}

TEST(FalconLoad, AnUnpluggedDeviceFailsWithWhatTheHostSaid) {
  FakeFalconLink link;
  link.unplugged = true;
  const LoadResult r = load_firmware(link, falcon_image_bytes(), 1, kFast);
  EXPECT_FALSE(r.loaded);
  EXPECT_EQ(describe(r),
            "try 1: FTDI request 'purge the receive FIFO' refused, saw LIBUSB_ERROR_NO_DEVICE");
}

TEST(FalconImage, AFileOfTheWrongSizeIsRefusedNamingItAndWhereNovintsAre) {
  const std::string path = ::testing::TempDir() + "falcon_image.bin";
  {
    std::ofstream out(path, std::ios::binary);
    out << "MZ this is an installer";
  }
  try {
    read_firmware_image(path);
    FAIL() << "a 23-byte file taken as a firmware image";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), path + ": 23 bytes is no Falcon firmware image")) << e.what();
    EXPECT_TRUE(contains(e.what(), "libnifalcon's firmware/ folder")) << e.what();
  }
  {
    std::ofstream out(path, std::ios::binary);
    const auto image = falcon_image_bytes();
    out.write(reinterpret_cast<const char*>(image.data()), static_cast<long>(image.size()));
  }
  EXPECT_EQ(read_firmware_image(path), falcon_image_bytes());
  std::remove(path.c_str());
  EXPECT_THROW(read_firmware_image(path), std::runtime_error);
}

}  // namespace
}  // namespace hapticd::drivers::falcon::testing
