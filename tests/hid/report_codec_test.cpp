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
  } cases[] = {{FieldType::kU8, 200},       {FieldType::kI8, -100},    {FieldType::kU16, 65000},
               {FieldType::kI16, -32000},   {FieldType::kU32, 4.0e9},  {FieldType::kI32, -2.0e9},
               {FieldType::kF32, -1.25e-3}, {FieldType::kU24, 16.0e6}, {FieldType::kI24, -8.0e6}};
  for (const auto& c : cases) {
    for (Endian e : {Endian::kLittle, Endian::kBig}) {
      std::uint8_t bytes[4] = {};
      write_raw(bytes, typed(c.type, 0, e), c.value);
      EXPECT_FLOAT_EQ(read_raw(bytes, typed(c.type, 0, e)), c.value) << to_string(c.type);
    }
  }
}

TEST(HidReportField, ByteOrderIsTheWireOrder) {
  std::uint8_t b[2] = {};
  write_raw(b, typed(FieldType::kI16), -2);  // 0xFFFE
  EXPECT_EQ(b[0], 0xFE);
  EXPECT_EQ(b[1], 0xFF);
  write_raw(b, typed(FieldType::kU16, 0, Endian::kBig), 0x1234);
  EXPECT_EQ(b[0], 0x12);
  EXPECT_EQ(b[1], 0x34);
}

TEST(HidReportField, IntegersRoundAndClampNeverWrap) {
  std::uint8_t b[2] = {};
  write_raw(b, typed(FieldType::kI16), 1e9);
  EXPECT_EQ(read_raw(b, typed(FieldType::kI16)), 32767);
  write_raw(b, typed(FieldType::kU8), -5);
  EXPECT_EQ(read_raw(b, typed(FieldType::kU8)), 0);
  write_raw(b, typed(FieldType::kI8), 2.6);
  EXPECT_EQ(read_raw(b, typed(FieldType::kI8)), 3);
  write_raw(b, typed(FieldType::kI16), std::nan(""));
  EXPECT_EQ(read_raw(b, typed(FieldType::kI16)), 0);
}

// Issue 34 item 5: the Nintendo Switch Pro Controller's input report 0x30 packs each stick's
// two 12-bit axes into three bytes, X = b5 | (b6 & 0x0f) << 8 and Y = b6 >> 4 | b7 << 4 in the
// data after the id (dekuNukem/Nintendo_Switch_Reverse_Engineering, bluetooth_hid_notes.md,
// "Standard input report - Stick data"; Linux hid-nintendo.c, joycon_report_left_stick:
// hid_field_extract(rep->left_stick, 0, 12) and (rep->left_stick + 1, 4, 12)).
TEST(HidReportField, TwelveBitAxesPackedThreeBytesToTwoAreReadAndWrittenApart) {
  FieldSpec x, y;
  x.byte = 5;
  x.bits = 12;
  y.byte = 6;
  y.bit = 4;
  y.bits = 12;
  std::uint8_t d[8] = {};
  write_raw(d, x, 0x9AB);
  write_raw(d, y, 0x123);
  EXPECT_EQ(d[5], 0xAB);
  EXPECT_EQ(d[6], 0x39);
  EXPECT_EQ(d[7], 0x12);
  EXPECT_EQ(read_raw(d, x), 0x9AB);
  EXPECT_EQ(read_raw(d, y), 0x123);
  write_raw(d, x, 0.0);
  EXPECT_EQ(read_raw(d, y), 0x123) << "writing X leaves Y's nibble alone";
  write_raw(d, x, 0x800);  // the stick centred
  // The nearest whole-byte layout, u16 at byte 5, reads Y's low nibble into X.
  EXPECT_EQ(read_raw(d, typed(FieldType::kU16, 5)), 0x3800);
  EXPECT_EQ(x.span(), 2u);
  EXPECT_EQ(x.mask_of_byte(6), 0x0F);
  EXPECT_EQ(y.mask_of_byte(6), 0xF0);
}

TEST(HidReportField, SignedAndBigEndianBitFieldsAnd24BitValues) {
  FieldSpec s;  // i12 from bit 4 of byte 1
  s.byte = 1;
  s.bit = 4;
  s.bits = 12;
  s.is_signed = true;
  std::uint8_t d[5] = {0x0F, 0x0F, 0, 0, 0};
  write_raw(d, s, -5);
  EXPECT_EQ(read_raw(d, s), -5);
  EXPECT_EQ(d[1] & 0x0F, 0x0F) << "the low nibble is another field's";
  write_raw(d, s, -1e6);
  EXPECT_EQ(read_raw(d, s), -2048) << "clamped to the field's range, never wrapped";
  FieldSpec b;  // big-endian: b0 << 4 | b1 >> 4
  b.bits = 12;
  b.bit = 4;
  b.endian = Endian::kBig;
  std::uint8_t e[2] = {0, 0x05};
  write_raw(e, b, 0xABC);
  EXPECT_EQ(e[0], 0xAB);
  EXPECT_EQ(e[1], 0xC5);
  EXPECT_EQ(read_raw(e, b), 0xABC);
  std::uint8_t t[3] = {};
  write_raw(t, typed(FieldType::kI24), -2);
  EXPECT_EQ(t[0], 0xFE);
  EXPECT_EQ(t[2], 0xFF);
  EXPECT_EQ(read_raw(t, typed(FieldType::kI24)), -2);
  EXPECT_EQ(raw_max(typed(FieldType::kI24)), 8388607.0);
}

ReportProfileLayout ffbeast_like() {
  ReportProfileLayout l;
  l.input.report_id = 1;
  l.input.length = 8;
  l.input.position = typed(FieldType::kI16, 0, Endian::kLittle, 1e-5);
  l.input.sequence = typed(FieldType::kU8, 2);
  l.input.status = typed(FieldType::kU8, 3);
  l.input.fault_mask = 0x01;
  l.output.report_id = 2;
  l.output.length = 8;
  l.output.force = typed(FieldType::kI16, 0, Endian::kLittle, 0.001);
  l.output.full_scale = 10000;
  l.output.enable = SwitchField{typed(FieldType::kU8, 2), 1, 0};
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

TEST(HidReportLayout, FieldsMayShareAByteButNotABit) {
  ReportProfileLayout l = ffbeast_like();
  l.input.position = FieldSpec{};
  l.input.position.bits = 12;
  l.input.position.scale = 1e-5;
  l.input.sequence = FieldSpec{};
  l.input.sequence->byte = 1;
  l.input.sequence->bit = 4;
  l.input.sequence->bits = 4;
  EXPECT_TRUE(validate(l, 10.0).empty()) << validate(l, 10.0).front();
  l.input.sequence->bit = 3;
  const auto e = validate(l, 10.0);
  EXPECT_TRUE(
      mentions(e,
               "input.sequence: byte 1 bits 3..6 overlap input.position (byte 0, byte 1 bits "
               "0..3)"))
      << e.front();
  l.input.sequence->bit = 4;
  l.input.sequence->bits = 40;
  EXPECT_TRUE(mentions(validate(l, 10.0), "input.sequence.bits: must be 1..32, got 40"));
}

TEST(HidReportLayout, AFourBitCounterWrapsAtSixteen) {
  ReportProfileLayout l = ffbeast_like();
  l.input.sequence = FieldSpec{};
  l.input.sequence->byte = 2;
  l.input.sequence->bit = 4;
  l.input.sequence->bits = 4;
  ASSERT_TRUE(validate(l, 10.0).empty());
  std::vector<std::uint8_t> r(input_report_size(l.input));
  encode_input({.position = {0.001}, .sequence = 17, .status = 0}, l.input, r);
  InputValues v;
  ASSERT_EQ(decode_input(r, l.input, v), InputDecode::kOk);
  EXPECT_EQ(v.sequence, 1u);
  EXPECT_EQ(counter_modulus(*l.input.sequence), 16u);
}

// Issue 34 item 1: a position that wraps is written modulo its width (the simulated device's
// side); the driver unwraps it. One that does not is clamped, as every other field.
TEST(HidReportLayout, AWrappingPositionIsWrittenModuloItsWidth) {
  ReportProfileLayout l = ffbeast_like();
  l.input.position = typed(FieldType::kI8, 0, Endian::kLittle, 1e-3);
  l.input.position_wraps = true;
  ASSERT_TRUE(validate(l, 10.0).empty());
  std::vector<std::uint8_t> r(input_report_size(l.input));
  encode_input({.position = {0.130}, .sequence = 0, .status = 0}, l.input, r);
  InputValues v;
  ASSERT_EQ(decode_input(r, l.input, v), InputDecode::kOk);
  EXPECT_EQ(v.position_count[0], 130 - 256);
  EXPECT_NEAR(v.position[0], -0.126, 1e-12);
  l.input.position_wraps = false;
  encode_input({.position = {0.130}, .sequence = 0, .status = 0}, l.input, r);
  ASSERT_EQ(decode_input(r, l.input, v), InputDecode::kOk);
  EXPECT_EQ(v.position_count[0], 127);
  l.input.position = typed(FieldType::kF32, 0, Endian::kLittle, 1.0);
  l.input.position_wraps = true;
  EXPECT_TRUE(mentions(validate(l, 10.0), "input.position.wraps: only an integer field wraps"));
}

TEST(HidReportLayout, AOneBitKeepaliveIsRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.output.keepalive = FieldSpec{};
  l.output.keepalive->byte = 3;
  l.output.keepalive->bits = 1;
  EXPECT_TRUE(mentions(validate(l, 10.0), "output.keepalive: one bit cannot"));
}

TEST(HidReportLayout, AFieldPastTheReportIsRefused) {
  ReportProfileLayout l = ffbeast_like();
  l.output.force = typed(FieldType::kI16, 7, Endian::kLittle, 0.001);
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
  l.output.force = typed(FieldType::kI32, 0, Endian::kLittle, std::numeric_limits<double>::max());
  EXPECT_TRUE(mentions(validate(l, 10.0), "is no finite force"));
}

// Found by fuzz/hid_codec_fuzzer.cpp: an f32 value is sent as the nearest float, so 1e-5 never
// reads back as the on value, and an off of 1e-300 went out as 0.0, the same as an on of 0.
TEST(HidReportLayout, AnF32SwitchValueMustBeAFloat) {
  ReportProfileLayout l = ffbeast_like();
  l.output.enable.reset();
  l.enable_feature = FeatureLayout{3, 4, typed(FieldType::kF32), 1e-5, 0.0};
  EXPECT_TRUE(mentions(validate(l, 10.0), "enable_feature: on/off values must be raw values"));
  l.enable_feature->on = 0.0;
  l.enable_feature->off = 1e-300;
  EXPECT_TRUE(mentions(validate(l, 10.0), "enable_feature: on/off values must be raw values"));
  l.enable_feature->off = 0.5;
  EXPECT_TRUE(validate(l, 10.0).empty());
}

TEST(HidReportLayout, CountersAndStatusMustBeIntegersAndIdsConsistent) {
  ReportProfileLayout l = ffbeast_like();
  l.input.sequence = typed(FieldType::kI8, 2);
  l.input.status = typed(FieldType::kF32, 4);
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
  l.enable_feature = FeatureLayout{3, 1, typed(FieldType::kU8), 1, 0};
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
  encode_input({.position = {-0.0123}, .sequence = 250, .status = 0x01}, l.input, r);
  EXPECT_EQ(r[0], 1);
  InputValues v;
  ASSERT_EQ(decode_input(r, l.input, v), InputDecode::kOk);
  EXPECT_NEAR(v.position[0], -0.0123, 1e-9);
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
  encode_input({.position = {0.001}, .sequence = 3, .status = 0}, l.input, in);
  InputValues v;
  ASSERT_EQ(decode_input(in, l.input, v), InputDecode::kOk);
  EXPECT_NEAR(v.position[0], 0.001, 1e-12);
  std::vector<std::uint8_t> out(wire_size(l.output.length));
  encode_force(std::array{2.5}, l.output, out);
  EXPECT_EQ(out[0], 0);
  OutputValues o;
  ASSERT_TRUE(decode_output(out, l.output, o));
  EXPECT_DOUBLE_EQ(o.force[0], 2.5);
}

TEST(HidReportLayout, ForceIsClampedToFullScale) {
  const ReportProfileLayout l = ffbeast_like();
  std::vector<std::uint8_t> out(wire_size(l.output.length));
  out[0] = 2;
  encode_force(std::array{-50.0}, l.output, out);
  OutputValues o;
  ASSERT_TRUE(decode_output(out, l.output, o));
  EXPECT_DOUBLE_EQ(o.force[0], -10.0);
}

}  // namespace
}  // namespace hapticd::drivers::hid
