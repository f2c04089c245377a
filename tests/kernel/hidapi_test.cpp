// hidapi against real kernel HID devices in the kernel test machine. Built twice, once per
// hidapi backend (the two libraries export the same symbols, so one binary holds one):
// HAPTICD_HIDAPI_HIDRAW=1 links libhidapi-hidraw, 0 links libhidapi-libusb.
#include <gtest/gtest.h>
#include <hidapi/hidapi.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hid_support.h"
#include "sysfs.h"
#include "uhid_device.h"
#include "usb_hid_gadget.h"

#if HAPTICD_HIDAPI_HIDRAW
#define HIDAPI_SUITE HidapiHidraw
#else
#define HIDAPI_SUITE HidapiLibusb
#endif

namespace hapticd::kernel_test {
namespace {

using Report = std::vector<std::uint8_t>;
using HidDevicePtr = std::unique_ptr<hid_device, decltype(&hid_close)>;

std::wstring or_empty(const wchar_t* text) { return text != nullptr ? text : L""; }
std::string narrow(const wchar_t* text) {
  const std::wstring wide = or_empty(text);
  return {wide.begin(), wide.end()};  // hidapi's messages are ASCII
}

struct Found {
  std::string path;
  std::wstring serial, manufacturer, product;
  int interface_number = -2;
};

// The one device hidapi enumerates with these ids, or a test failure.
std::optional<Found> enumerate_one(std::uint16_t vid, std::uint16_t pid) {
  hid_device_info* list = hid_enumerate(vid, pid);
  std::optional<Found> found;
  int count = 0;
  for (const hid_device_info* info = list; info != nullptr; info = info->next, ++count) {
    found = Found{info->path, or_empty(info->serial_number), or_empty(info->manufacturer_string),
                  or_empty(info->product_string), info->interface_number};
  }
  hid_free_enumeration(list);
  EXPECT_EQ(count, 1) << "hid_enumerate found " << count << " devices";
  return found;
}

// The driver bound to a USB interface (the last part of its driver link), or "".
std::string interface_driver(const std::string& interface_dir) {
  char target[256] = {};
  const ssize_t n = ::readlink((interface_dir + "/driver").c_str(), target, sizeof target - 1);
  if (n <= 0) return "";
  const std::string link(target, static_cast<std::size_t>(n));
  return link.substr(link.rfind('/') + 1);
}

#if HAPTICD_HIDAPI_HIDRAW
// hidraw reaches the device through usbhid, which stays bound to the interface.
constexpr const char* kDriverWhileOpen = "usbhid";
std::string interface_dir(const std::string& hidraw) {
  return "/sys/class/hidraw/" + hidraw.substr(hidraw.rfind('/') + 1) + "/device/..";
}
#else
// libusb claims the interface itself: usbhid is detached and usbfs holds it. hidapi-libusb's
// path "bus-port:config.interface" is the interface's name in sysfs.
constexpr const char* kDriverWhileOpen = "usbfs";
std::string interface_dir(const std::string& path) { return "/sys/bus/usb/devices/" + path; }
#endif

Report numbered(std::uint8_t id, std::uint8_t seed) {
  Report report{id};
  for (std::uint8_t i = 0; i < 8; ++i) report.push_back(static_cast<std::uint8_t>(seed + 3 * i));
  return report;
}

Report read_report(hid_device* dev) {
  Report buf(64);
  const int n = hid_read_timeout(dev, buf.data(), buf.size(), 5000);
  EXPECT_GT(n, 0) << "hid_read_timeout: " << (n < 0 ? narrow(hid_error(dev)) : "timed out");
  buf.resize(static_cast<std::size_t>(std::max(n, 0)));
  return buf;
}

// hid_init() after the device exists: the guest runs no udevd, and libusb (built with udev
// support) learns of devices plugged in after its initialisation only from udevd's events.
class HidapiSession {
 public:
  HidapiSession() { EXPECT_EQ(hid_init(), 0); }
  ~HidapiSession() { hid_exit(); }
  HidapiSession(const HidapiSession&) = delete;
  HidapiSession& operator=(const HidapiSession&) = delete;
};

TEST(HIDAPI_SUITE, UsbGadgetEnumeratedAndExchangesReports) {
  UsbHidGadgetConfig config;
  config.report_descriptor = vendor_report_descriptor({});
  config.vendor_id = 0x1209;
  config.product_id = 0x0001;
  config.serial = "hapticd-usb-7";
  UsbHidGadget gadget(config);
  HidapiSession hidapi;
  const auto found = enumerate_one(0x1209, 0x0001);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->serial, L"hapticd-usb-7");
  EXPECT_EQ(found->manufacturer, L"hapticd");
  EXPECT_EQ(found->product, L"hapticd test device");
  EXPECT_EQ(found->interface_number, 0);
#if HAPTICD_HIDAPI_HIDRAW
  EXPECT_EQ(found->path, gadget.hidraw_path());
#endif

  EXPECT_EQ(interface_driver(interface_dir(found->path)), "usbhid");
  HidDevicePtr dev(hid_open_path(found->path.c_str()), &hid_close);
  ASSERT_NE(dev, nullptr) << "hid_open_path " << found->path;
  EXPECT_EQ(interface_driver(interface_dir(found->path)), kDriverWhileOpen);

  const Report input = numbered(1, 0x21);
  gadget.write_input_report(input);
  EXPECT_EQ(read_report(dev.get()), input);

  const Report output = numbered(2, 0x52);
  ASSERT_EQ(hid_write(dev.get(), output.data(), output.size()), static_cast<int>(output.size()));
  EXPECT_EQ(gadget.read_output_report(), output);
}

#if HAPTICD_HIDAPI_HIDRAW
// uhid devices have no USB device behind them, so only the hidraw backend can see them.
TEST(HIDAPI_SUITE, UhidDeviceEnumeratedAndExchangesReports) {
  UhidConfig config;
  config.report_descriptor = vendor_report_descriptor({});
  config.vendor_id = 0x1209;
  config.product_id = 0x0002;
  config.name = "hapticd uhid test device";
  config.serial = "hapticd-uhid-3";
  UhidDevice uhid(config);
  HidapiSession hidapi;
  const auto found = enumerate_one(0x1209, 0x0002);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->serial, L"hapticd-uhid-3");
  EXPECT_EQ(found->product, L"hapticd uhid test device");
  EXPECT_EQ(found->path, uhid.hidraw_path());

  HidDevicePtr dev(hid_open_path(found->path.c_str()), &hid_close);
  ASSERT_NE(dev, nullptr) << "hid_open_path " << found->path;
  const Report input = numbered(1, 0x05);
  uhid.send_input(input);
  EXPECT_EQ(read_report(dev.get()), input);

  const Report output = numbered(2, 0x90);
  ASSERT_EQ(hid_write(dev.get(), output.data(), output.size()), static_cast<int>(output.size()));
  EXPECT_EQ(uhid.read_output(), output);
  EXPECT_TRUE(uhid.is_open());
}
#endif

}  // namespace
}  // namespace hapticd::kernel_test
