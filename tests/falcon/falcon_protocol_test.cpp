// The Falcon's wire as libnifalcon (github libnifalcon/libnifalcon) speaks it. The expected
// bytes are written out by hand from src/firmware/FalconFirmwareNovintSDK.cpp: '<', each
// motor's 16 bits as four nibbles least significant first, each plus 0x41, byte 13 the LEDs
// and the homing bit (out) or homing bits 4-6 and grip bits 0-3 (in), byte 14 0x41, '>'.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "drivers/falcon/falcon_protocol.h"

namespace hapticd::drivers::falcon {
namespace {

Packet packet(const std::string& s) {
  Packet p{};
  EXPECT_EQ(s.size(), kPacketBytes) << s;
  for (std::size_t i = 0; i < kPacketBytes && i < s.size(); ++i) {
    p[i] = static_cast<unsigned char>(s[i]);
  }
  return p;
}

std::string text(const Packet& p) { return std::string(p.begin(), p.end()); }

// One IN transfer as the FT232 sends it: 2 modem status bytes before each 64-byte packet's data.
std::vector<unsigned char> transfer(const std::string& data) {
  std::vector<unsigned char> out;
  for (std::size_t i = 0; i < data.size(); i += kUsbPacketBytes - kModemStatusBytes) {
    out.push_back(0x31);  // the status the chip reports: CTS, DSR
    out.push_back(0x60);  // transmitter empty
    const std::string part = data.substr(i, kUsbPacketBytes - kModemStatusBytes);
    out.insert(out.end(), part.begin(), part.end());
  }
  return out;
}

TEST(FalconPacket, ACommandIsEachMotorsNibblesLeastFirstThenTheLedsAndHomingBit) {
  Command c;
  c.motor = {0x1234, -1, 0};
  c.leds = kLedGreen | kLedRed;
  c.homing = true;
  // 0x1234: 4 3 2 1 -> E D C B; 0xFFFF: P P P P; 0: A A A A; 0x2 | 0x8 | 0x1 = 11 -> L.
  EXPECT_EQ(text(encode_command(c)), "<EDCBPPPPAAAALA>");
  c.homing = false;
  c.leds = 0;
  c.motor = {-32768, 32767, 0x00F0};
  EXPECT_EQ(text(encode_command(c)), "<AAAIPPPHAPAAAA>");
}

TEST(FalconPacket, AStateGivesSignedEncodersTheHomedMotorsAndTheGrip) {
  // -300 = 0xFED4: D4 -> E(4) N(13) O(14) P(15); 1234 = 0x04D2: C(2) N(13) E(4) A(0);
  // byte 13: homed 0b101, grip 0b0010 -> 0x52 + 0x41 = 0x93.
  Packet p = packet("<ENOPAAAACNEA?A>");
  p[13] = 0x93;
  State s;
  ASSERT_EQ(decode_state(p, s), PacketError::kNone);
  EXPECT_EQ(s.encoder[0], -300);
  EXPECT_EQ(s.encoder[1], 0);
  EXPECT_EQ(s.encoder[2], 1234);
  EXPECT_EQ(s.homed, 0b101);
  EXPECT_EQ(s.grip, 0b0010);
}

TEST(FalconPacket, EveryCountSurvivesTheWire) {
  for (int v = -32768; v <= 32767; v += 7) {
    Command c;
    c.motor = {static_cast<std::int16_t>(v), static_cast<std::int16_t>(-v - 1),
               static_cast<std::int16_t>(v / 3)};
    State s;
    ASSERT_EQ(decode_state(encode_command(c), s), PacketError::kNone);
    ASSERT_EQ(s.encoder, c.motor) << v;
  }
}

TEST(FalconPacket, ACorruptedByteIsRefusedNotMasked) {
  State s;
  s.encoder = {7, 7, 7};
  Packet p = packet("<AAAAAAAAAAAAAA>");
  ASSERT_EQ(decode_state(p, s), PacketError::kNone);
  for (std::size_t i = 1; i < 15; ++i) {
    Packet bad = p;
    bad[i] = i == 13 ? 0xC1 : 0x51;  // one past each byte's range ('A' + 0x7F, 'P')
    EXPECT_EQ(decode_state(bad, s), PacketError::kBadNibble) << "byte " << i;
    bad[i] = 0x40;
    EXPECT_EQ(decode_state(bad, s), PacketError::kBadNibble) << "byte " << i;
  }
  p[13] = 0xC0;  // every homing and grip bit: in range
  EXPECT_EQ(decode_state(p, s), PacketError::kNone);
  EXPECT_EQ(s.homed, 0x7);
  EXPECT_EQ(s.grip, 0xF);
}

TEST(FalconStream, ModemStatusBytesAreDroppedAtEachUsbPacket) {
  PacketStream stream;
  // Four packets: 64 bytes of data cross the first 64-byte USB packet's end.
  std::string data;
  for (int i = 0; i < 4; ++i) data += "<ABCDEFGHIJKLA" + std::string(1, char('A' + i)) + ">";
  const auto t = transfer(data);
  ASSERT_EQ(t.size(), 64u + 4u);
  stream.feed_transfer(t);
  Packet p;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(stream.next(p)) << i;
    EXPECT_EQ(p[14], 'A' + i);
  }
  EXPECT_FALSE(stream.next(p));
  EXPECT_EQ(stream.skipped_bytes(), 0u);
  stream.feed_transfer(transfer(""));  // the status alone, every latency period
  EXPECT_FALSE(stream.next(p));
}

TEST(FalconStream, AFrameSplitAcrossTransfersIsWhole) {
  PacketStream stream;
  Packet p;
  stream.feed_transfer(transfer("<AAAAB"));
  EXPECT_FALSE(stream.next(p));
  stream.feed_transfer(transfer("BBBCCCCAA>"));
  ASSERT_TRUE(stream.next(p));
  EXPECT_EQ(text(p), "<AAAABBBBCCCCAA>");
  EXPECT_EQ(stream.skipped_bytes(), 0u);
}

// libnifalcon reads every later packet from the wrong offset once a byte is lost; the scan
// finds the next frame and counts what it skipped.
TEST(FalconStream, ALostByteCostsOneFrameAndIsCounted) {
  PacketStream stream;
  const std::string good = "<AAAABBBBCCCCAA>";
  std::string broken = good;
  broken.erase(5, 1);  // 15 bytes: its '>' arrives where the next frame's first byte is
  stream.feed_transfer(transfer(broken + good + good));
  Packet p;
  ASSERT_TRUE(stream.next(p));
  EXPECT_EQ(text(p), good);
  ASSERT_TRUE(stream.next(p));
  EXPECT_EQ(text(p), good);
  EXPECT_FALSE(stream.next(p));
  EXPECT_EQ(stream.skipped_bytes(), 15u);
}

TEST(FalconStream, AReaderFarBehindCountsWhatItCouldNotKeep) {
  PacketStream stream;
  std::string many;
  for (int i = 0; i < 10; ++i) many += "<AAAABBBBCCCCAA>";
  stream.feed_transfer(transfer(many));
  EXPECT_EQ(stream.overflowed_bytes(), 2 * kPacketBytes);
  Packet p;
  int frames = 0;
  while (stream.next(p)) ++frames;
  EXPECT_EQ(frames, 8);
}

TEST(FalconBootloader, TheFirstCheckAcceptsTheReplyOfEitherHost) {
  const std::vector<unsigned char> linux_reply = {0x0A, 0x44, 0x2C, 0x0D};
  const std::vector<unsigned char> mac_reply = {0x00, 0x0A, 0x44, 0x2C, 0x0D};
  EXPECT_TRUE(is_check_reply(linux_reply));
  EXPECT_TRUE(is_check_reply(mac_reply));
  EXPECT_FALSE(is_check_reply(std::vector<unsigned char>{0x0A, 0x44, 0x2C}));
  EXPECT_FALSE(is_check_reply(std::vector<unsigned char>{0x0A, 0x43, 0x2C, 0x0D}));
  EXPECT_FALSE(is_check_reply(std::vector<unsigned char>{}));
}

// The order matters to the chip: DTR pulsed low then high resets the microcontroller into its
// bootloader, at 9600 baud with a 16 ms latency timer; the firmware runs at divisor 2 with 1 ms.
TEST(FalconBootloader, TheSetupResetsIntoTheBootloaderAndNormalModeIsFast) {
  const auto setup = bootloader_setup();
  ASSERT_GE(setup.size(), 2u);
  EXPECT_EQ(setup[setup.size() - 2].value, 0x0100);  // DTR low
  EXPECT_EQ(setup.back().value, 0x0101);             // DTR high
  bool latency16 = false, baud9600 = false;
  for (const FtdiRequest& r : setup) {
    latency16 |= r.request == 9 && r.value == 16;
    baud9600 |= r.request == 3 && r.value == 0x4138;
  }
  EXPECT_TRUE(latency16 && baud9600);
  EXPECT_EQ(loading_rate().back().value, 0x15);
  const auto normal = normal_mode();
  EXPECT_EQ(normal[0].request, 9);
  EXPECT_EQ(normal[0].value, 1);
  EXPECT_EQ(normal[1].request, 3);
  EXPECT_EQ(normal[1].value, 2);
}

TEST(FalconCounts, ZeroCountsIsTheArmAt35DegreesAndADegreeIsAbout27Counts) {
  EXPECT_NEAR(arm_angle(0), 35.0 * std::numbers::pi / 180.0, 1e-12);
  // 1280 counts a turn of a 14.25 mm shaft over a 110 mm drum: 1280 * 110 / 14.25 / 360.
  const double per_degree = 1280.0 * 110.0 / 14.25 / 360.0;
  EXPECT_NEAR(per_degree, 27.446, 1e-3);
  EXPECT_NEAR(arm_angle(1000) - arm_angle(0), 1000 / per_degree * std::numbers::pi / 180.0, 1e-12);
  EXPECT_LT(arm_angle(-32768), arm_angle(32767));
}

}  // namespace
}  // namespace hapticd::drivers::falcon
