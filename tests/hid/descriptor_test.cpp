// The report descriptor parser and the PID layout found in it: what a real force-feedback
// descriptor yields, every malformed form refused with the byte named, and a PID device that
// lacks a report refused with the report named.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/pid_protocol.h"
#include "drivers/hid/report_descriptor.h"

namespace hapticd::drivers::hid {
namespace {

std::string parse_error(std::vector<std::uint8_t> bytes) {
  const DescriptorParse p = parse_report_descriptor(bytes);
  EXPECT_FALSE(p.descriptor.has_value());
  return p.error;
}

TEST(HidDescriptor, TheReferencePidDeviceParsesIntoItsReports) {
  const auto p = parse_report_descriptor(pid_reference_descriptor());
  ASSERT_TRUE(p.descriptor) << p.error;
  const ParsedDescriptor& d = *p.descriptor;
  EXPECT_TRUE(d.numbered);
  ASSERT_EQ(d.applications.size(), 1u);
  EXPECT_EQ(d.applications[0], usage(0x01, 0x04));  // Joystick
  const ReportInfo* pos = d.find_report(ReportKind::kInput, 0x05);
  ASSERT_NE(pos, nullptr);
  EXPECT_EQ(pos->data_bytes(), 3u);  // X (16 bit) and the sequence byte
  const ReportInfo* effect = d.find_report(ReportKind::kOutput, 0x31);
  ASSERT_NE(effect, nullptr);
  EXPECT_EQ(effect->data_bytes(), 15u);  // index, type, 4 x 16 bit, gain, trigger, axes, dir
  EXPECT_NE(d.find_report(ReportKind::kFeature, 0x42), nullptr);
  EXPECT_EQ(d.find_report(ReportKind::kInput, 0x42), nullptr);
}

TEST(HidDescriptor, PidLayoutIsFoundByUsageWhateverTheIds) {
  PidReferenceOptions o;
  o.ids.set_constant = 0x99;
  o.ids.block_load = 0x07;
  const auto p = parse_report_descriptor(pid_reference_descriptor(o));
  ASSERT_TRUE(p.descriptor) << p.error;
  const PidFind f = find_pid_layout(*p.descriptor, kGenericDesktopX, kReferenceSequenceUsage);
  ASSERT_TRUE(f.layout) << f.error;
  const PidLayout& l = *f.layout;
  EXPECT_EQ(l.set_constant.id, 0x99);
  EXPECT_EQ(l.block_load.id, 0x07);
  EXPECT_EQ(l.block_load.kind, ReportKind::kFeature);
  EXPECT_EQ(l.sc_magnitude.logical_min, -10000);
  EXPECT_EQ(l.sc_magnitude.logical_max, 10000);
  EXPECT_TRUE(l.sc_magnitude.is_signed);
  EXPECT_EQ(l.se_constant.value, 1);  // the first of the Effect Type array's usages
  EXPECT_EQ(l.dc_enable.value, 1);    // DC Enable Actuators, from a usage range
  EXPECT_EQ(l.dc_stop_all.value, 3);
  EXPECT_EQ(l.eo_stop.value, 3);
  EXPECT_EQ(l.se_direction.logical_max, 35999);
  EXPECT_TRUE(l.se_axis_x.present);
  EXPECT_TRUE(l.state.present);
  EXPECT_EQ(l.positions.at(0).bit_size, 16u);
  EXPECT_EQ(l.sequence.bit_offset, 16u);
}

// A stick of two axes (OpenFFBoard's "FFB Joystick (2 Axis)" shape): both positions in one
// report, Axes Enable X and Y, and the Direction's two instances, each its own 16 bits.
TEST(PidDescriptor, TwoAxesFindEachAxisItsEnableAndItsDirection) {
  PidReferenceOptions o;
  o.axes = 2;
  const auto p = parse_report_descriptor(pid_reference_descriptor(o));
  ASSERT_TRUE(p.descriptor) << p.error;
  const std::uint32_t xy[] = {kGenericDesktopX, kGenericDesktopY};
  const PidFind f = find_pid_layout(*p.descriptor, xy, kReferenceSequenceUsage);
  ASSERT_TRUE(f.layout) << f.error;
  const PidLayout& l = *f.layout;
  ASSERT_EQ(l.positions.size(), 2u);
  EXPECT_EQ(l.positions[1].bit_offset, 16u) << "Y after X";
  EXPECT_EQ(l.sequence.bit_offset, 32u);
  EXPECT_EQ(l.se_axis_y.bit_offset, l.se_axis_x.bit_offset + 1);
  EXPECT_EQ(l.se_direction_enable.bit_offset, l.se_axis_x.bit_offset + 2)
      << "bit 2, as OpenFFBoard";
  EXPECT_EQ(l.se_direction_y.bit_offset, l.se_direction.bit_offset + 16);
  EXPECT_EQ(l.se_direction_y.logical_max, 36000);
  EXPECT_EQ(direction_value(l.se_direction, 0.0), 0);
  EXPECT_EQ(direction_value(l.se_direction_y, 360.0), 36000);
  EXPECT_EQ(direction_value(l.se_direction, 90.0), 9000);

  // A one-axis descriptor cannot take two effects of their own axes: the gap is named.
  const auto one = parse_report_descriptor(pid_reference_descriptor());
  const std::uint32_t xx[] = {kGenericDesktopX, kGenericDesktopX};
  const PidFind none = find_pid_layout(*one.descriptor, xx);
  ASSERT_FALSE(none.layout);
  EXPECT_NE(none.error.find("Axes Enable Y"), std::string::npos) << none.error;
  // Y missing from the position's report is named with its key.
  const PidFind no_y = find_pid_layout(*one.descriptor, xy);
  ASSERT_FALSE(no_y.layout);
  EXPECT_NE(no_y.error.find("(device.hid.pid.positions[1])"), std::string::npos) << no_y.error;
}

// Every report the profile cannot do without, taken out of the descriptor in turn.
TEST(HidDescriptor, APidDeviceWithoutANeededReportIsRefusedNamingIt) {
  const auto p = parse_report_descriptor(pid_reference_descriptor());
  ASSERT_TRUE(p.descriptor);
  const struct {
    pid::Usage collection;
    const char* name;
  } needed[] = {{pid::kSetEffectReport, "Set Effect"},
                {pid::kSetConstantForceReport, "Set Constant Force"},
                {pid::kEffectOperationReport, "Effect Operation"},
                {pid::kDeviceControlReport, "Device Control"},
                {pid::kCreateNewEffectReport, "Create New Effect"},
                {pid::kBlockLoadReport, "Block Load"}};
  for (const auto& n : needed) {
    ParsedDescriptor d = *p.descriptor;
    std::erase_if(d.fields, [&](const ReportField& f) { return f.inside(pid::u(n.collection)); });
    const PidFind f = find_pid_layout(d, kGenericDesktopX);
    EXPECT_FALSE(f.layout);
    EXPECT_NE(f.error.find(std::string("no PID ") + n.name + " report"), std::string::npos)
        << f.error;
  }
  const PidFind x = find_pid_layout(*p.descriptor, usage(0x01, 0x31));  // Y: not there
  EXPECT_NE(x.error.find("no input field with the position usage 0x01:0x31"), std::string::npos);
}

TEST(HidDescriptor, LogicalMaximumIsUnsignedUnlessTheMinimumIsNegative) {
  DescriptorBuilder b;
  b.usage_page(0xFF00).usage(1).logical(0, 255).report_size(8).report_count(1).input(2);
  b.logical(-127, 127).input(2);
  const auto p = parse_report_descriptor(b.bytes());
  ASSERT_TRUE(p.descriptor);
  EXPECT_EQ(p.descriptor->fields[0].logical_max, 255);
  EXPECT_EQ(p.descriptor->fields[1].logical_min, -127);
  EXPECT_EQ(p.descriptor->fields[1].logical_max, 127);
  EXPECT_EQ(p.descriptor->fields[1].bit_offset, 8u);
  EXPECT_FALSE(p.descriptor->numbered);
}

TEST(HidDescriptor, PushPopAndLongItemsAreFollowed) {
  const std::vector<std::uint8_t> d = {
      0x06, 0x00, 0xFF,              // Usage Page 0xFF00
      0x75, 0x08, 0x95, 0x02,        // Report Size 8, Count 2
      0xA4,                          // Push
      0x75, 0x10,                    // Report Size 16
      0xFE, 0x02, 0x10, 0xAA, 0xBB,  // a long item: skipped
      0xB4,                          // Pop: size 8 again
      0x09, 0x01, 0x81, 0x02,        // Usage 1, Input
  };
  const auto p = parse_report_descriptor(d);
  ASSERT_TRUE(p.descriptor) << p.error;
  EXPECT_EQ(p.descriptor->fields.at(0).bit_size, 8u);
  EXPECT_EQ(p.descriptor->fields.at(0).usages.at(0), 0xFF000001u);
}

TEST(HidDescriptor, MalformedDescriptorsAreRefusedWithTheByteNamed) {
  EXPECT_EQ(parse_error({}), "the report descriptor is empty");
  EXPECT_EQ(parse_error({0x05, 0x01, 0x06, 0x00}),
            "byte 2: item 0x06 needs 2 data bytes; the descriptor ends first");
  EXPECT_EQ(parse_error({0xC0}), "byte 0: End Collection without a Collection");
  EXPECT_EQ(parse_error({0xB4}), "byte 0: Pop without a Push");
  EXPECT_EQ(parse_error({0x85, 0x00}), "byte 0: Report ID 0: must be 1..255");
  EXPECT_EQ(parse_error({0x75, 0x00}), "byte 0: Report Size 0 bits: must be 1..256");
  EXPECT_EQ(parse_error({0x95, 0x01, 0x81, 0x02}), "byte 2: input item with no Report Size");
  EXPECT_EQ(parse_error({0x05, 0x01, 0xA1, 0x01}),
            "1 collection(s) still open at the end of the descriptor");
  EXPECT_EQ(parse_error({0xFE, 0x05, 0x10, 0x00}), "byte 0: long item cut short");
  EXPECT_EQ(parse_error({0x29, 0x05}), "byte 0: Usage Maximum without a Usage Minimum");
  EXPECT_EQ(parse_error({0xF4}), "byte 0: unknown global item tag 15");
}

TEST(HidDescriptor, AbsurdSizesAreRefusedNotFollowed) {
  EXPECT_EQ(parse_error({0x96, 0x88, 0x13}), "byte 0: Report Count 5000: more than 4096");
  EXPECT_EQ(parse_error(std::vector<std::uint8_t>(5000, 0xA4)),
            "the report descriptor is 5000 bytes, more than any device has (4096)");
  // 16 x 4096 x 256 bits: far past any report.
  std::vector<std::uint8_t> big = {0x75, 0xFF, 0x96, 0x00, 0x10};
  big.insert(big.end(), {0x81, 0x02, 0x81, 0x02});
  EXPECT_NE(parse_error(big).find("grows past 4096 bytes"), std::string::npos);
  // A usage range of 65536 usages.
  EXPECT_NE(parse_error({0x19, 0x00, 0x2A, 0xFF, 0xFF}).find("usage range of 65536 usages"),
            std::string::npos);
  std::vector<std::uint8_t> deep;
  for (int i = 0; i < 70; ++i) deep.insert(deep.end(), {0xA1, 0x02});  // 70 nested collections
  EXPECT_EQ(parse_error(deep), "byte 128: collections nested too deep");
}

TEST(HidDescriptor, FieldsBeforeTheFirstReportIdAreRefusedInANumberedDescriptor) {
  DescriptorBuilder b;
  b.usage_page(0xFF00).usage(1).report_size(8).report_count(1).input(2);
  b.report_id(3).usage(2).input(2);
  EXPECT_NE(parse_error(b.bytes()).find("before any Report ID"), std::string::npos);
}

// Found by fuzz/hid_codec_fuzzer.cpp: all ones reads -1, inside a signed range such as the
// reference Magnitude's -10000..10000; an end of the width is outside it.
TEST(HidDescriptor, NullValueReadsOutsideTheLogicalRangeWheneverAValueDoes) {
  const auto read_null = [](std::uint32_t bits, std::int64_t min, std::int64_t max) {
    const Slot s{true, 0, bits, min, max, min < 0};
    std::vector<std::uint8_t> data(4, 0);
    set_slot(data, s, null_value(s));
    return get_slot(data, s);
  };
  EXPECT_EQ(read_null(16, 0, 32767), 65535);  // Duration: infinite
  EXPECT_EQ(read_null(8, 1, 8), 255);         // Trigger Button: none
  EXPECT_EQ(read_null(8, 1, 255), 0);
  EXPECT_EQ(read_null(16, -10000, 10000), -32768);
  EXPECT_EQ(read_null(8, -128, 126), 127);
  EXPECT_EQ(read_null(8, -128, 127), -1);  // every value is in range: there is no null
}

TEST(HidDescriptor, BitsPackLittleEndianAndStayInsideTheBuffer) {
  std::vector<std::uint8_t> data(2, 0);
  put_bits(data, 3, 7, 0x55);
  EXPECT_EQ(get_bits(data, 3, 7), 0x55u);
  EXPECT_EQ(data[0], 0xA8);
  EXPECT_EQ(data[1], 0x02);
  put_bits(data, 12, 32, 0xFFFFFFFF);  // runs off the end: only 4 bits written
  EXPECT_EQ(data[1], 0xF2);
  EXPECT_EQ(get_bits(data, 12, 32), 0xFu);
  EXPECT_EQ(field_value(0xFF, 8, true), -1);
  EXPECT_EQ(field_value(0x7F, 7, true), -1);
  EXPECT_EQ(field_value(0xFF, 8, false), 255);
}

}  // namespace
}  // namespace hapticd::drivers::hid
