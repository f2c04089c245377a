// The `report` profile's codec: fields of every type and byte order, the layout validation a
// person meets in `hapticd check`, and decoding reports of the wrong id or length.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "drivers/hid/report_layout.h"

namespace hapticd::drivers::hid {
namespace {

TEST(HidReportField, EveryTypeRoundTripsInBothByteOrders) {
  const struct {
    FieldType type;
    double value;
  } cases[] = {{FieldType::kU8, 200},      {FieldType::kI8, -100},   {FieldType::kU16, 65000},
               {FieldType::kI16, -32000},  {FieldType::kU32, 4.0e9}, {FieldType::kI32, -2.0e9},
               {FieldType::kF32, -1.25e-3}};
  for (const auto& c : cases) {
    for (Endian e : {Endian::kLittle, Endian::kBig}) {
      std::uint8_t bytes[4] = {};
      write_raw(bytes, c.type, e, c.value);
      EXPECT_FLOAT_EQ(read_raw(bytes, c.type, e), c.value) << to_string(c.type);
    }
  }
}

TEST(HidReportField, ByteOrderIsTheWireOrder) {
  std::uint8_t b[2] = {};
  write_raw(b, FieldType::kI16, Endian::kLittle, -2);  // 0xFFFE
  EXPECT_EQ(b[0], 0xFE);
  EXPECT_EQ(b[1], 0xFF);
  write_raw(b, FieldType::kU16, Endian::kBig, 0x1234);
  EXPECT_EQ(b[0], 0x12);
  EXPECT_EQ(b[1], 0x34);
}

TEST(HidReportField, IntegersRoundAndClampNeverWrap) {
  std::uint8_t b[2] = {};
  write_raw(b, FieldType::kI16, Endian::kLittle, 1e9);
  EXPECT_EQ(read_raw(b, FieldType::kI16, Endian::kLittle), 32767);
  write_raw(b, FieldType::kU8, Endian::kLittle, -5);
  EXPECT_EQ(read_raw(b, FieldType::kU8, Endian::kLittle), 0);
  write_raw(b, FieldType::kI8, Endian::kLittle, 2.6);
  EXPECT_EQ(read_raw(b, FieldType::kI8, Endian::kLittle), 3);
  write_raw(b, FieldType::kI16, Endian::kLittle, std::nan(""));
  EXPECT_EQ(read_raw(b, FieldType::kI16, Endian::kLittle), 0);
}

ReportProfileLayout ffbeast_like() {
  ReportProfileLayout l;
  l.input = {1, 8, {0, FieldType::kI16, Endian::kLittle, 1e-5, 0.0}, {}, {}, 0, {}};
  l.input.sequence = FieldSpec{2, FieldType::kU8};
  l.input.status = FieldSpec{3, FieldType::kU8};
  l.input.fault_mask = 0x01;
  l.output.report_id = 2;
  l.output.length = 8;
  l.output.force = {0, FieldType::kI16, Endian::kLittle, 0.001, 0.0};
  l.output.full_scale = 10000;
  l.output.enable = SwitchField{{2, FieldType::kU8}, 1, 0};
  return l;
}

TEST(HidReportLayout, TheExampleLayoutIsValid) {
  EXPECT_TRUE(validate(ffbeast_like(), 10.0).empty());
}

bool mentions(const std::vector<std::string>& errors, const std::string& what) {
  for (const std::string& e : errors) {
    if (e.find(what) != std::string::npos) return true;
  }
  return false;
}

TEST(HidReportLayout, OverlappingFieldsAreRefusedNamingBoth) {
  ReportProfileLayout l = ffbeast_like();
  l.input.sequence->byte = 1;  // inside the i16 position
  const auto e = validate(l, 10.0);
  EXPECT_TRUE(mentions(e, "input.sequence: bytes 1..1 overlap input.position (bytes 0..1)"))
      << e.front();
}

TEST(HidReportLayout, AFieldPastTheReportIsRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.output.force = {7, FieldType::kI16, Endian::kLittle, 0.001, 0.0};
  EXPECT_TRUE(mentions(validate(l, 10.0), "output.force: bytes 7..8 lie past the report's 8"));
}

TEST(HidReportLayout, AForceScaleThatCannotReachMaxForceIsRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.output.full_scale = 5000;  // 5 N
  EXPECT_TRUE(mentions(validate(l, 10.0), "cannot represent device.max_force +-10 N"));
  EXPECT_TRUE(validate(l, 5.0).empty());
  l.output.full_scale = 40000;  // does not fit an i16
  EXPECT_TRUE(mentions(validate(l, 10.0), "full_scale: must be > 0 and fit the field's type i16"));
}

// Found by fuzz/hid_codec_fuzzer.cpp: 127.5 counts of an i16 were sent as 128, past the limit.
TEST(HidReportLayout, AFractionalFullScaleOfAnIntegerForceIsRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.output.full_scale = 10000.5;
  EXPECT_TRUE(mentions(validate(l, 10.0),
                       "full_scale: must be > 0 and fit the field's type i16 (whole counts"));
}

// Found by the hid_codec fuzz target: a force scale of DBL_MAX passed (it reaches any
// max_force), but full scale is then no finite force, and +inf commanded decoded as inf.
TEST(HidReportLayout, AForceScaleWhoseFullScaleIsNoFiniteForceIsRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.output.force.type = FieldType::kI32;
  l.output.force.scale = std::numeric_limits<double>::max();
  EXPECT_TRUE(mentions(validate(l, 10.0), "is no finite force"));
}

// Found by fuzz/hid_codec_fuzzer.cpp: an f32 value is sent as the nearest float, so 1e-5 never
// reads back as the on value, and an off of 1e-300 went out as 0.0, the same as an on of 0.
TEST(HidReportLayout, AnF32SwitchValueMustBeAFloat) {
  ReportProfileLayout l = ffbeast_like();
  l.output.enable.reset();
  l.enable_feature = FeatureLayout{3, 4, {0, FieldType::kF32}, 1e-5, 0.0};
  EXPECT_TRUE(mentions(validate(l, 10.0), "enable_feature: on/off values must be raw values"));
  l.enable_feature->on = 0.0;
  l.enable_feature->off = 1e-300;
  EXPECT_TRUE(mentions(validate(l, 10.0), "enable_feature: on/off values must be raw values"));
  l.enable_feature->off = 0.5;
  EXPECT_TRUE(validate(l, 10.0).empty());
}

TEST(HidReportLayout, CountersAndStatusMustBeIntegersAndIdsConsistent) {
  ReportProfileLayout l = ffbeast_like();
  l.input.sequence->type = FieldType::kI8;
  l.input.status->type = FieldType::kF32;
  l.input.status->byte = 4;
  l.output.report_id = 0;
  const auto e = validate(l, 10.0);
  EXPECT_TRUE(mentions(e, "input.sequence: type must be an unsigned integer"));
  EXPECT_TRUE(mentions(e, "input.status: type must be an integer"));
  EXPECT_TRUE(mentions(e, "output.report_id: a device numbers all its reports or none"));
}

TEST(HidReportLayout, AnAmplifierSwitchIsRequired) {
  ReportProfileLayout l = ffbeast_like();
  l.output.enable.reset();
  EXPECT_TRUE(mentions(validate(l, 10.0), "needs an enable field or an enable_feature"));
  l.enable_feature = FeatureLayout{3, 1, {0, FieldType::kU8}, 1, 0};
  EXPECT_TRUE(validate(l, 10.0).empty());
}

TEST(HidReportLayout, AbsurdLengthsAreRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.input.length = 0;
  l.output.length = 100000;
  const auto e = validate(l, 10.0);
  EXPECT_TRUE(mentions(e, "input.length: must be 1..1024"));
  EXPECT_TRUE(mentions(e, "output.length: must be 1..1024"));
}

TEST(HidReportLayout, InputDecodesAndRejectsWrongIdsAndShortReports) {
  const ReportProfileLayout l = ffbeast_like();
  std::vector<std::uint8_t> r(input_report_size(l.input));
  encode_input({-0.0123, 0.0, 250, 0x01}, l.input, r);
  EXPECT_EQ(r[0], 1);
  InputValues v;
  ASSERT_EQ(decode_input(r, l.input, v), InputDecode::kOk);
  EXPECT_NEAR(v.position, -0.0123, 1e-9);
  EXPECT_EQ(v.sequence, 250u);
  EXPECT_EQ(v.status, 1u);
  r[0] = 7;
  EXPECT_EQ(decode_input(r, l.input, v), InputDecode::kOtherReport);
  r[0] = 1;
  EXPECT_EQ(decode_input(std::span(r).first(5), l.input, v), InputDecode::kTooShort);
  EXPECT_EQ(decode_input({}, l.input, v), InputDecode::kEmpty);
}

TEST(HidReportLayout, UnnumberedDevicesCarryNoIdOnInputButAZeroOnOutput) {
  ReportProfileLayout l = ffbeast_like();
  l.input.report_id = 0;
  l.output.report_id = 0;
  EXPECT_TRUE(validate(l, 10.0).empty());
  EXPECT_EQ(input_report_size(l.input), 8u);
  std::vector<std::uint8_t> in(8);
  encode_input({0.001, 0.0, 3, 0}, l.input, in);
  InputValues v;
  ASSERT_EQ(decode_input(in, l.input, v), InputDecode::kOk);
  EXPECT_NEAR(v.position, 0.001, 1e-12);
  std::vector<std::uint8_t> out(wire_size(l.output.length));
  encode_force(2.5, l.output, out);
  EXPECT_EQ(out[0], 0);
  OutputValues o;
  ASSERT_TRUE(decode_output(out, l.output, o));
  EXPECT_DOUBLE_EQ(o.force, 2.5);
}

TEST(HidReportLayout, ForceIsClampedToFullScale) {
  const ReportProfileLayout l = ffbeast_like();
  std::vector<std::uint8_t> out(wire_size(l.output.length));
  out[0] = 2;
  encode_force(-50.0, l.output, out);
  OutputValues o;
  ASSERT_TRUE(decode_output(out, l.output, o));
  EXPECT_DOUBLE_EQ(o.force, -10.0);
}

}  // namespace
}  // namespace hapticd::drivers::hid
