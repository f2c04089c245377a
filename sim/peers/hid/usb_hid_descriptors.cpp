#include "sim/peers/hid/usb_hid_descriptors.h"

#include <stdexcept>

namespace hapticd::sim::hid {
namespace {

// USB 2.0 chapter 9 and HID 1.11 section 6.2 numbers.
constexpr std::uint8_t kDeviceType = 0x01, kConfigurationType = 0x02, kStringType = 0x03,
                       kInterfaceType = 0x04, kEndpointType = 0x05, kHidType = 0x21,
                       kReportType = 0x22;
constexpr std::uint8_t kHidClass = 0x03, kInterrupt = 0x03;

std::uint8_t lo(unsigned v) { return static_cast<std::uint8_t>(v & 0xFF); }
std::uint8_t hi(unsigned v) { return static_cast<std::uint8_t>((v >> 8) & 0xFF); }

std::vector<std::uint8_t> endpoint(std::uint8_t address) {
  return {7,
          kEndpointType,
          address,
          kInterrupt,
          lo(UsbHidDescriptors::kMaxPacket),
          hi(UsbHidDescriptors::kMaxPacket),
          1 /* bInterval: 1 ms at full speed */};
}

}  // namespace

UsbHidDescriptors make_usb_hid_descriptors(const DeviceIdentity& identity,
                                           std::vector<std::uint8_t> report_descriptor) {
  if (report_descriptor.size() > 0xFFFF) {
    throw std::invalid_argument("usb descriptors: the report descriptor is over 65535 bytes");
  }
  for (const std::string* s : {&identity.serial, &identity.manufacturer, &identity.name}) {
    if (s->size() > 126) throw std::invalid_argument("usb descriptors: string over 126 chars");
  }
  UsbHidDescriptors d;
  d.identity = identity;
  d.device = {18,
              kDeviceType,
              0x00,
              0x02,  // USB 2.0
              0,
              0,
              0,   // the class is the interface's
              64,  // bMaxPacketSize0
              lo(identity.vendor_id),
              hi(identity.vendor_id),
              lo(identity.product_id),
              hi(identity.product_id),
              0x00,
              0x01,  // bcdDevice 1.00
              1,
              2,
              3,   // manufacturer, product, serial strings
              1};  // one configuration
  const unsigned length = static_cast<unsigned>(report_descriptor.size());
  d.hid = {9, kHidType, 0x11,        0x01,  // HID 1.11
           0, 1,        kReportType, lo(length), hi(length)};
  d.in_endpoint = endpoint(UsbHidDescriptors::kInEndpoint);
  d.out_endpoint = endpoint(UsbHidDescriptors::kOutEndpoint);
  const std::vector<std::uint8_t> interface = {9, kInterfaceType, 0, 0, 2, kHidClass, 0, 0, 0};
  const unsigned total = 9 + 9 + 9 + 7 + 7;
  d.configuration = {
      9,    kConfigurationType, lo(total), hi(total), 1, UsbHidDescriptors::kConfiguration, 0,
      0x80,  // bus powered
      50};   // 100 mA
  const std::vector<std::uint8_t>* parts[] = {&interface, &d.hid, &d.in_endpoint, &d.out_endpoint};
  for (const std::vector<std::uint8_t>* part : parts) {
    d.configuration.insert(d.configuration.end(), part->begin(), part->end());
  }
  d.report = std::move(report_descriptor);
  return d;
}

std::optional<std::vector<std::uint8_t>> UsbHidDescriptors::string(std::uint8_t index) const {
  if (index == 0) return std::vector<std::uint8_t>{4, kStringType, 0x09, 0x04};  // en-US
  const std::string* text = index == 1   ? &identity.manufacturer
                            : index == 2 ? &identity.name
                            : index == 3 ? &identity.serial
                                         : nullptr;
  if (text == nullptr) return std::nullopt;
  std::vector<std::uint8_t> s{static_cast<std::uint8_t>(2 + 2 * text->size()), kStringType};
  for (const char c : *text) s.insert(s.end(), {static_cast<std::uint8_t>(c), 0});
  return s;
}

}  // namespace hapticd::sim::hid
