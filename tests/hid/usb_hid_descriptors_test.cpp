// The USB descriptors the raw gadget peer enumerates with: what usbhid and libusb parse.
#include <gtest/gtest.h>

#include <stdexcept>

#include "drivers/hid/descriptor_builder.h"
#include "sim/peers/hid/usb_hid_descriptors.h"

namespace hapticd::sim::hid {
namespace {

TEST(UsbHidDescriptors, OneInterruptInAndOutHidInterfaceWithTheReportDescriptorsLength) {
  DeviceIdentity id;
  id.vendor_id = 0x1209;
  id.product_id = 0xffb1;
  const std::vector<std::uint8_t> report = drivers::hid::pid_reference_descriptor();
  const UsbHidDescriptors d = make_usb_hid_descriptors(id, report);
  ASSERT_EQ(d.device.size(), 18u);
  EXPECT_EQ(d.device[8] | d.device[9] << 8, 0x1209);
  EXPECT_EQ(d.device[10] | d.device[11] << 8, 0xffb1);
  ASSERT_EQ(d.configuration.size(), 41u);
  EXPECT_EQ(d.configuration[2] | d.configuration[3] << 8, 41);  // wTotalLength
  EXPECT_EQ(d.configuration[9 + 4], 2);                         // bNumEndpoints
  EXPECT_EQ(d.configuration[9 + 5], 0x03);                      // HID class
  EXPECT_EQ(d.hid[7] | d.hid[8] << 8, static_cast<int>(report.size()));
  EXPECT_EQ(d.in_endpoint[2], 0x81);
  EXPECT_EQ(d.out_endpoint[2], 0x02);
  EXPECT_EQ(d.in_endpoint[6], 1) << "polled every 1 ms at full speed";
  // Every descriptor in the configuration starts where the previous one's length ends.
  std::size_t at = 0, parts = 0;
  while (at < d.configuration.size()) {
    at += d.configuration[at];
    ++parts;
  }
  EXPECT_EQ(at, d.configuration.size());
  EXPECT_EQ(parts, 5u);
  EXPECT_EQ(d.report, report);
}

TEST(UsbHidDescriptors, StringsAreUtf16WithTheLanguageListFirst) {
  DeviceIdentity id;
  id.serial = "kt";
  const UsbHidDescriptors d = make_usb_hid_descriptors(id, {0x05, 0x01});
  EXPECT_EQ(*d.string(0), (std::vector<std::uint8_t>{4, 3, 0x09, 0x04}));
  EXPECT_EQ(*d.string(3), (std::vector<std::uint8_t>{6, 3, 'k', 0, 't', 0}));
  EXPECT_FALSE(d.string(4).has_value());
  id.serial.assign(127, 'x');
  EXPECT_THROW(make_usb_hid_descriptors(id, {}), std::invalid_argument);
}

}  // namespace
}  // namespace hapticd::sim::hid
