// Which attached device a configuration means, and what `hapticd devices` tells a person.
#include <gtest/gtest.h>

#include "drivers/hid/device_select.h"
#include "wiring/registry.h"

namespace hapticd::drivers::hid {
namespace {

std::vector<DeviceListing> attached() {
  DeviceListing wheel{"/dev/hidraw0", 0x1209, 0xffb0, 0x100, "A1", "FFBeast",
                      "Wheel",        0,      0x01,   0x04,  "usb"};
  DeviceListing twin = wheel;
  twin.path = "/dev/hidraw1";
  twin.serial = "B2";
  DeviceListing keyboard{"/dev/hidraw2", 0x046d, 0xc31c, 0,    "",   "Logitech",
                         "Keyboard",     0,      0x01,   0x06, "usb"};
  return {wheel, twin, keyboard};
}

TEST(HidSelect, OneMatchIsOpenedSeveralAskForMoreNoneListsWhatIsThere) {
  Selector s;
  s.vendor_id = 0x1209;
  s.product_id = 0xffb0;
  Selection r = select_one(s, attached(), "hidraw");
  EXPECT_FALSE(r.device);
  EXPECT_NE(r.error.find("2 HID devices match device.hid.select (vendor_id 0x1209, product_id "
                         "0xffb0); add serial, interface or path"),
            std::string::npos)
      << r.error;
  s.serial = "B2";
  r = select_one(s, attached(), "hidraw");
  ASSERT_TRUE(r.device) << r.error;
  EXPECT_EQ(r.device->path, "/dev/hidraw1");
  s.serial = "C3";
  r = select_one(s, attached(), "hidraw");
  EXPECT_NE(r.error.find("no HID device matches"), std::string::npos);
  EXPECT_NE(r.error.find("046d:c31c 'Keyboard'"), std::string::npos) << r.error;
  EXPECT_NE(select_one(s, {}, "libusb").error.find("none is attached"), std::string::npos);
  Selector by_path;
  by_path.path = "/dev/hidraw2";
  by_path.vendor_id = 0x1209;  // the path alone decides
  EXPECT_EQ(select_one(by_path, attached(), "hidraw").device->product, "Keyboard");
}

TEST(HidSelect, TheListingGivesEachDeviceTheKeysThatPickItOut) {
  const std::string text = format_listing(attached(), "hidraw");
  EXPECT_NE(text.find("device.hid: {backend: hidraw, select: {vendor_id: 0x1209, product_id: "
                      "0xffb0, serial: \"A1\"}}"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("{vendor_id: 0x046d, product_id: 0xc31c}"), std::string::npos) << text;
  EXPECT_EQ(format_listing({}, "libusb"), "  (none)\n");
}

// hidapi lists a PID device once per top-level collection: one device, one entry.
TEST(HidSelect, ADeviceListedOncePerCollectionIsOneEntryNamingEachUsage) {
  std::vector<DeviceListing> all = attached();
  DeviceListing pid_collection = all[2];
  pid_collection.usage_page = 0x0f;
  pid_collection.usage = 0x7d;
  all.push_back(pid_collection);
  const std::string text = format_listing(all, "hidraw");
  EXPECT_NE(text.find("usage 0x0001:0x0006, 0x000f:0x007d at /dev/hidraw2"), std::string::npos)
      << text;
  EXPECT_EQ(text.find("/dev/hidraw2", text.find("/dev/hidraw2") + 1), std::string::npos) << text;
  EXPECT_NE(text.find("{vendor_id: 0x046d, product_id: 0xc31c}"), std::string::npos) << text;
}

TEST(HidSelect, TheDevicesCommandAsksBothBackends) {
  const wiring::DriverEntry& hid = wiring::find_driver("hid");
  ASSERT_NE(hid.list_devices, nullptr);
  const std::string text = hid.list_devices();
  EXPECT_NE(text.find("hid (hidraw backend):"), std::string::npos) << text;
  EXPECT_NE(text.find("hid (libusb backend):"), std::string::npos) << text;
}

}  // namespace
}  // namespace hapticd::drivers::hid
