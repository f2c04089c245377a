// Writes HID report descriptors: the smallest encoding of each item, the way a firmware
// author writes them by hand. The loopback peer describes itself with these (a vendor
// descriptor for a `report` layout, a PID force-feedback device for `pid`), the kernel tests
// give them to the USB gadget and uhid, and the parser's tests build what they parse. Pure.
#pragma once

#include <cstdint>
#include <vector>

#include "drivers/hid/report_descriptor.h"
#include "drivers/hid/report_layout.h"

namespace hapticd::drivers::hid {

class DescriptorBuilder {
 public:
  DescriptorBuilder& usage_page(std::uint16_t page) { return unsigned_item(1, 0x0, page); }
  DescriptorBuilder& usage(std::uint16_t id) { return unsigned_item(2, 0x0, id); }
  DescriptorBuilder& usage_min(std::uint16_t id) { return unsigned_item(2, 0x1, id); }
  DescriptorBuilder& usage_max(std::uint16_t id) { return unsigned_item(2, 0x2, id); }
  // Logical/Physical Minimum and Maximum; the maximum is written unsigned when min >= 0, as
  // parsers read it.
  DescriptorBuilder& logical(std::int64_t min, std::int64_t max) { return range(0x1, min, max); }
  DescriptorBuilder& physical(std::int64_t min, std::int64_t max) { return range(0x3, min, max); }
  DescriptorBuilder& report_size(std::uint32_t bits) { return unsigned_item(1, 0x7, bits); }
  DescriptorBuilder& report_id(std::uint8_t id) { return unsigned_item(1, 0x8, id); }
  DescriptorBuilder& report_count(std::uint32_t n) { return unsigned_item(1, 0x9, n); }
  DescriptorBuilder& input(std::uint32_t flags) { return unsigned_item(0, 0x8, flags); }
  DescriptorBuilder& output(std::uint32_t flags) { return unsigned_item(0, 0x9, flags); }
  DescriptorBuilder& feature(std::uint32_t flags) { return unsigned_item(0, 0xB, flags); }
  // 0 physical, 1 application, 2 logical.
  DescriptorBuilder& collection(std::uint8_t type) { return unsigned_item(0, 0xA, type); }
  DescriptorBuilder& end_collection() {
    bytes_.push_back(0xC0);
    return *this;
  }
  // `bits` of padding (a constant field) in a report of `kind`.
  DescriptorBuilder& padding(ReportKind kind, std::uint32_t bits);
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  DescriptorBuilder& unsigned_item(std::uint8_t type, std::uint8_t tag, std::uint32_t value);
  DescriptorBuilder& signed_item(std::uint8_t type, std::uint8_t tag, std::int64_t value);
  DescriptorBuilder& range(std::uint8_t tag, std::int64_t min, std::int64_t max);
  void emit(std::uint8_t type, std::uint8_t tag, std::uint32_t value, std::uint8_t size);

  std::vector<std::uint8_t> bytes_;
};

// A vendor-defined descriptor (page 0xFF00) with the layout's input, output and feature
// reports as byte arrays: what a device with this layout would declare.
std::vector<std::uint8_t> report_profile_descriptor(const ReportProfileLayout& layout);

// The report ids of pid_reference_descriptor(): deliberately not the ones most firmwares use,
// so a driver that hard-codes ids fails against it.
struct PidReferenceIds {
  std::uint8_t position = 0x05, state = 0x06;
  std::uint8_t set_effect = 0x31, set_envelope = 0x32, set_constant = 0x35, effect_operation = 0x3A,
               block_free = 0x3B, device_control = 0x3C, device_gain = 0x3D;
  std::uint8_t create_effect = 0x41, block_load = 0x42, pool = 0x43;
};

struct PidReferenceOptions {
  bool sequence = true;      // a vendor sample counter (0xFF00:0x20, u8) beside the axis
  bool state_report = true;  // the PID State input report
  PidReferenceIds ids;
  // false: Device Control as the SideWinder-lineage firmwares declare it (adapt-ffb-joy,
  // ArduinoJoystickWithFFBLibrary, Fino, VNWheel): a logical collection of usage 0x96 holding
  // its array, with no 0x95 report collection around it.
  bool device_control_report = true;
  // 2: a stick of two axes as OpenFFBoard's "FFB Joystick (2 Axis)" declares it: X and Y in the
  // input report, Axes Enable X and Y, and two Direction instances of 0..36000.
  int axes = 1;
};

// The ids ArduinoJoystickWithFFBLibrary v1.0.0 gives its reports (src/FFBDescriptor.h), one id
// shared by reports of different kinds: input 1 and Set Effect, PID State and Set Envelope 2,
// Create New Effect and Set Constant Force 5, Block Load 6, PID Pool 7.
inline constexpr PidReferenceIds kSideWinderLineageIds{1, 2, 1, 2, 5, 10, 11, 12, 13, 5, 6, 7};

// A one-axis force-feedback joystick on the PID page (HID PID 1.0): Generic Desktop X (16 bit,
// +-32767) in the input report, one effect type (constant force), and every report a PID host
// needs for it: those the `pid` profile uses, and Set Envelope and the PID Pool feature report
// that Linux's own PID host (hid-pidff) requires before it offers FF_CONSTANT through evdev.
std::vector<std::uint8_t> pid_reference_descriptor(const PidReferenceOptions& options = {});

// The vendor usage of the sequence counter in pid_reference_descriptor().
inline constexpr std::uint32_t kReferenceSequenceUsage = 0xFF000020u;

}  // namespace hapticd::drivers::hid
