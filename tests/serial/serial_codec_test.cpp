// The serial driver's pure codecs: every check reproduces its catalogue's value, frames round-
// trip through fields of any shape, and the scanner finds frames in a stream cut anywhere,
// through noise, damaged frames and sync bytes inside payloads, counting what it skipped.
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <string_view>
#include <vector>

#include "drivers/serial/serial_frame.h"

namespace hapticd::drivers::serial {
namespace {

std::span<const std::uint8_t> bytes(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(SerialCheck, EveryAlgorithmGivesItsCatalogueCheckValue) {
  for (const CheckAlgorithm& a : check_algorithms()) {
    if (a.kind != CheckKind::kCrc) continue;
    EXPECT_EQ(compute_check(a, bytes("123456789")), a.crc.check) << a.name;
  }
  // The 8-bit sum and XOR of "123456789" (0x31..0x39): 477 mod 256 and 0x31.
  EXPECT_EQ(compute_check(*find_check_algorithm("sum8"), bytes("123456789")), 477 % 256);
  EXPECT_EQ(compute_check(*find_check_algorithm("xor8"), bytes("123456789")), 0x31);
  EXPECT_EQ(find_check_algorithm("crc-32"), nullptr);
}

// The streaming format of config/serial-stream.yaml (docs/drivers/serial.md).
InputLayout stream_input() {
  InputLayout in;
  in.shape.sync = {0xA5, 0x5A};
  in.shape.length = 14;
  in.shape.check =
      FrameCheck{find_check_algorithm("crc-16/ibm-3740"), 12, 2, 12, field::Endian::kBig};
  in.positions = {field::typed(field::FieldType::kI24, 3, field::Endian::kBig, 1e-3),
                  field::typed(field::FieldType::kI24, 6, field::Endian::kBig, 1e-3)};
  in.sequence = field::typed(field::FieldType::kU8, 2);
  in.status = field::typed(field::FieldType::kU8, 9);
  return in;
}

TEST(SerialFrame, AnInputFrameRoundTripsAndItsCheckIsTheCatalogues) {
  const InputLayout in = stream_input();
  EXPECT_TRUE(validate(in, "input").empty());
  std::array<std::uint8_t, kMaxFrame> f{};
  InputValues v;
  v.position = {-1.234, 8.0, 0.0};
  v.sequence = 77;
  v.status = 2;
  encode_input(v, in, f);
  EXPECT_EQ(f[0], 0xA5);
  EXPECT_EQ(f[1], 0x5A);
  EXPECT_EQ(f[3], 0xFF) << "-1234 counts, big-endian: FF FB 2E";
  EXPECT_EQ(f[5], 0x2E);
  const std::uint16_t crc = compute_check(*in.shape.check->algorithm, std::span(f).subspan(2, 10));
  EXPECT_EQ(f[12], crc >> 8) << "stored big-endian";
  EXPECT_EQ(f[13], crc & 0xFF);
  ASSERT_TRUE(check_ok(in.shape, std::span(f).first(14)));
  InputValues back;
  decode_input(std::span(f).first(14), in, back);
  EXPECT_DOUBLE_EQ(back.position[0], -1.234);
  EXPECT_DOUBLE_EQ(back.position[1], 8.0);
  EXPECT_EQ(back.sequence, 77u);
  EXPECT_EQ(back.status, 2u);
  f[4] ^= 0x10;
  EXPECT_FALSE(check_ok(in.shape, std::span(f).first(14))) << "one bit flipped";
}

TEST(SerialFrame, OutputFramesClampToTheFieldAndCarryTheEnableSwitch) {
  OutputLayout out;
  out.shape.sync = {0x02, 0x05};
  out.shape.length = 10;
  out.forces = {field::typed(field::FieldType::kF32, 2),
                field::typed(field::FieldType::kI16, 6, field::Endian::kBig, 0.001)};
  out.enable = EnableField{field::FieldSpec{8, 0, 1}, 1.0, 0.0};
  ASSERT_TRUE(validate(out, "output").empty());
  std::array<std::uint8_t, kMaxFrame> f{};
  const std::array<double, 2> forces{0.5, 100.0};
  encode_output(forces, true, out, f);
  OutputValues v;
  decode_output(std::span(f).first(10), out, v);
  EXPECT_FLOAT_EQ(static_cast<float>(v.force[0]), 0.5f);
  EXPECT_DOUBLE_EQ(v.force[1], 32.767) << "clamped to what an i16 of mN m holds";
  EXPECT_TRUE(v.enable);
  encode_output(forces, false, out, f);
  decode_output(std::span(f).first(10), out, v);
  EXPECT_FALSE(v.enable);
}

TEST(SerialFrame, LayoutsThatCannotBeAreRefusedAtTheKeyToChange) {
  InputLayout in = stream_input();
  in.positions[1] = field::typed(field::FieldType::kU8, 12);  // over the check
  auto e = validate(in, "input");
  ASSERT_GE(e.size(), 1u);
  EXPECT_EQ(e[0], "input.positions[1]: byte 12 is also check's");
  in = stream_input();
  in.positions[0].byte = 12;  // ends past the frame
  in.positions[0] = field::typed(field::FieldType::kI24, 12, field::Endian::kBig);
  EXPECT_EQ(validate(in, "input").at(0),
            "input.positions[0]: ends at byte 15, past the frame's 14");
  in = stream_input();
  in.positions[0].byte = 1;  // over the sync
  EXPECT_EQ(validate(in, "input").at(0), "input.positions[0]: byte 1 is also sync's");
  in = stream_input();
  in.shape.check->from = 10;  // covers itself
  in.shape.check->to = 14;
  EXPECT_EQ(validate(in, "input").at(0),
            "input.check: the bytes it covers include the check itself");
  in = stream_input();
  in.status = field::typed(field::FieldType::kI8, 9);
  EXPECT_EQ(validate(in, "input").at(0),
            "input.status: an unsigned integer field (a u8, u16, bits: N)");
}

// A stream of good frames cut into random pieces, with noise between them, damaged frames,
// and frames whose payload holds the sync bytes.
TEST(SerialScanner, FindsEveryGoodFrameWhereverTheStreamIsCut) {
  const InputLayout in = stream_input();
  std::vector<std::uint8_t> stream;
  std::mt19937 rng(7);
  std::array<std::uint8_t, kMaxFrame> f{};
  int good = 0, damaged = 0;
  for (int k = 0; k < 250; ++k) {  // within the u8 sequence's wrap
    InputValues v;
    v.sequence = static_cast<std::uint32_t>(k);
    // Sync bytes A5 5A inside the payload: count 0xA55A5A.
    v.position[0] = k % 7 == 0 ? static_cast<double>(-0x5AA5A6) * 1e-3 : k * 1e-3;
    encode_input(v, in, f);
    if (k % 11 == 5) {
      f[7] ^= 0x40;  // damaged in transit
      ++damaged;
    } else {
      ++good;
    }
    stream.insert(stream.end(), f.begin(), f.begin() + 14);
    if (k % 13 == 3) stream.insert(stream.end(), {0x00, 0xA5, 0x13, 0xA5});  // noise
  }
  FrameScanner scanner(in.shape);
  int found = 0;
  std::uint32_t last = 0;
  for (std::size_t at = 0; at < stream.size();) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % 40, stream.size() - at);
    scanner.push(std::span(stream).subspan(at, n));
    at += n;
    for (auto frame = scanner.next(); !frame.empty(); frame = scanner.next()) {
      InputValues v;
      decode_input(frame, in, v);
      EXPECT_TRUE(found == 0 || v.sequence > last) << "in order, none twice";
      last = v.sequence;
      EXPECT_NE(v.sequence % 11, 5u) << "a damaged frame is never taken";
      ++found;
    }
  }
  EXPECT_EQ(found, good);
  EXPECT_EQ(scanner.counts().frames, static_cast<std::uint64_t>(good));
  EXPECT_GE(scanner.counts().bad_check, static_cast<std::uint64_t>(damaged));
  EXPECT_GT(scanner.counts().skipped, 0u);
  EXPECT_EQ(scanner.counts().overflowed, 0u);
}

TEST(SerialScanner, MoreThanItHoldsKeepsTheNewestAndCountsTheRest) {
  const InputLayout in = stream_input();
  FrameScanner scanner(in.shape);
  std::vector<std::uint8_t> flood(5000, 0x11);
  std::array<std::uint8_t, kMaxFrame> f{};
  InputValues v;
  v.sequence = 9;
  encode_input(v, in, f);
  std::copy_n(f.begin(), 14, flood.end() - 14);
  scanner.push(flood);
  const auto frame = scanner.next();
  ASSERT_EQ(frame.size(), 14u) << "the newest frame survives the flood";
  EXPECT_EQ(scanner.counts().overflowed, 5000u - 8 * kMaxFrame) << "it holds 2 KB";
  EXPECT_TRUE(scanner.next().empty());
}

}  // namespace
}  // namespace hapticd::drivers::serial
