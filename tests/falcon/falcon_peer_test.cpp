// The simulated Falcon (sim/peers/falcon/) over a real socketpair, from a host written in the
// test: the bootloader answers each check only in its state and at its rate and echoes the
// image; the firmware starts only after a plausible image; each command packet is answered by
// one state packet whose encoders move the way the firmware's torque pushes; homing; the faults.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "drivers/falcon/falcon_protocol.h"
#include "falcon_peer_rig.h"

namespace hapticd::sim::falcon::testing {
namespace {

constexpr std::uint16_t kDivisorCheck = 0x4138, kDivisorLoad = 0x15;
const std::vector<unsigned char> kA{df::kLoadCheck};
const std::vector<unsigned char> kReply(df::kCheckReply.begin(), df::kCheckReply.end());

// The bootloader from a DTR pulse to the end of the image, by hand.
void load_by_hand(SocketFalconHost& h, std::size_t image_bytes) {
  ASSERT_TRUE(h.requests(df::bootloader_setup()));
  ASSERT_TRUE(h.out(df::kCheckSend));
  ASSERT_EQ(h.data(), kReply);
  ASSERT_TRUE(h.requests(df::loading_rate()));
  ASSERT_TRUE(h.out(kA));
  ASSERT_EQ(h.data(), kA);
  const auto image = falcon_image_bytes(image_bytes);
  for (std::size_t at = 0; at < image.size(); at += df::kLoadChunkBytes) {
    const auto chunk =
        std::span(image).subspan(at, std::min(df::kLoadChunkBytes, image.size() - at));
    ASSERT_TRUE(h.out(chunk));
    ASSERT_TRUE(std::ranges::equal(h.data(), chunk)) << "the echo at byte " << at;
  }
  ASSERT_TRUE(h.requests(df::normal_mode()));
}

// One command packet out; the state packets that came back.
std::vector<df::State> exchange(SocketFalconHost& h, const df::Command& c) {
  EXPECT_TRUE(h.out(df::encode_command(c)));
  df::PacketStream stream;
  stream.feed_data(h.data());
  std::vector<df::State> states;
  df::Packet p;
  while (stream.next(p)) {
    df::State s;
    EXPECT_EQ(df::decode_state(p, s), df::PacketError::kNone);
    states.push_back(s);
  }
  return states;
}

df::State one_state(SocketFalconHost& h, const df::Command& c) {
  const auto states = exchange(h, c);
  EXPECT_EQ(states.size(), 1u) << "one state packet for each command packet";
  return states.empty() ? df::State{} : states.front();
}

TEST(FalconPeer, TheFirstCheckIsAnsweredOnlyAtItsRate) {
  Rig rig;
  SocketFalconHost& h = *rig.host;
  ASSERT_TRUE(h.requests(df::bootloader_setup()));
  EXPECT_EQ(rig.peer->resets(), 1);
  ASSERT_TRUE(h.control(3, kDivisorLoad));
  ASSERT_TRUE(h.out(df::kCheckSend));
  EXPECT_TRUE(h.data().empty()) << "the check at the loading rate reads as garbage";
  ASSERT_TRUE(h.control(3, kDivisorCheck));
  ASSERT_TRUE(h.out(kA));
  EXPECT_TRUE(h.data().empty()) << "the second check at 9600 baud";
  ASSERT_TRUE(h.out(df::kCheckSend));
  EXPECT_EQ(h.data(), kReply);
  EXPECT_EQ(h.last_transfer()[0], 0x31) << "the modem status leads the transfer";
  EXPECT_EQ(h.last_transfer()[1], 0x60);
  EXPECT_EQ(h.last_transfer().size(), df::kModemStatusBytes + kReply.size());
}

TEST(FalconPeer, TheSecondCheckNeedsDtrLowAndTheLoadingRateThenEveryByteIsEchoed) {
  Rig rig;
  SocketFalconHost& h = *rig.host;
  ASSERT_TRUE(h.requests(df::bootloader_setup()));
  ASSERT_TRUE(h.control(3, kDivisorLoad));  // DTR still high
  ASSERT_TRUE(h.out(kA));
  EXPECT_TRUE(h.data().empty());
  ASSERT_TRUE(h.requests(df::loading_rate()));
  ASSERT_TRUE(h.out(kA));
  EXPECT_EQ(h.data(), kA);
  const auto bytes = falcon_image_bytes(300);  // more than a USB packet holds: several transfers
  const int before = h.transfers();
  ASSERT_TRUE(h.out(bytes));
  EXPECT_EQ(h.data(), bytes);
  EXPECT_EQ(h.transfers() - before, 5) << "62 data bytes a USB packet";
  EXPECT_EQ(rig.peer->chip().image_bytes(), 300u);
  EXPECT_EQ(rig.peer->chip().mode(), McuMode::kLoading);
}

TEST(FalconPeer, AnImplausibleImageStartsNothing) {
  for (const std::size_t bytes : {std::size_t{0}, std::size_t{1000}, df::kFirmwareMaxBytes + 1}) {
    SCOPED_TRACE(bytes);
    Rig rig;
    load_by_hand(*rig.host, bytes);
    EXPECT_EQ(rig.peer->chip().mode(), McuMode::kSilent);
    EXPECT_FALSE(rig.peer->firmware_running());
    EXPECT_TRUE(exchange(*rig.host, df::Command{}).empty());
    EXPECT_EQ(rig.peer->loads_completed(), 0);
  }
}

TEST(FalconPeer, APlausibleImageStartsTheFirmwareWhichAnswersEachPacketOnce) {
  Rig rig;
  load_by_hand(*rig.host, 7914);
  EXPECT_TRUE(rig.peer->firmware_running());
  EXPECT_EQ(rig.peer->loads_completed(), 1);
  for (int i = 0; i < 5; ++i) one_state(*rig.host, df::Command{});
  EXPECT_EQ(rig.peer->packets_answered(), 5u);
  EXPECT_EQ(rig.peer->packets_taken(), 5u);
  // A packet cut across two transfers is taken whole once its end arrives.
  const df::Packet p = df::encode_command(df::Command{});
  ASSERT_TRUE(rig.host->out(std::span(p).first(7)));
  EXPECT_TRUE(rig.host->data().empty());
  ASSERT_TRUE(rig.host->out(std::span(p).subspan(7)));
  EXPECT_EQ(rig.host->data().size(), df::kPacketBytes);
}

TEST(FalconPeer, TheEncodersMoveTheWayTheFirmwaresTorquePushes) {
  for (const std::int16_t counts : {std::int16_t{500}, std::int16_t{-500}}) {
    SCOPED_TRACE(counts);
    Rig rig({}, {kLightHand});
    load_by_hand(*rig.host, 7914);
    const df::State start = one_state(*rig.host, df::Command{});
    EXPECT_FALSE(rig.peer->output_on()) << "zero counts: the amplifier off";
    df::Command push;
    push.motor = {counts, 0, 0};
    df::State s;
    for (int i = 0; i < 50; ++i) s = one_state(*rig.host, push);
    // tau = counts / kCountsPerNewtonMetre: a positive count turns the arm to smaller angles.
    const double tau = counts / df::kCountsPerNewtonMetre;
    EXPECT_TRUE(rig.peer->output_on());
    EXPECT_DOUBLE_EQ(rig.peer->applied_force(), std::abs(tau));
    const double q0 = rig.peer->joint_plant()->joint_positions()[0];
    EXPECT_EQ(s.encoder[0], df::counts_at_angle(q0) + kUnhomedOffsetCounts);
    EXPECT_GT(std::abs(s.encoder[0] - start.encoder[0]), 100) << "the arm turned";
    EXPECT_EQ(s.encoder[0] > start.encoder[0], tau > 0) << "the way the torque pushes";
    one_state(*rig.host, df::Command{});
    EXPECT_FALSE(rig.peer->output_on());
    EXPECT_EQ(rig.peer->applied_force(), 0.0);
  }
}

TEST(FalconPeer, TheEncodersAreRelativeUntilTheHomingBitHasBeenSentLongEnough) {
  FalconPeerOptions o;
  o.homing_packets = 20;
  Rig rig(o);
  load_by_hand(*rig.host, 7914);
  df::Command c;
  c.leds = df::kLedRed;
  const auto absolute = [&] {
    return df::counts_at_angle(rig.peer->joint_plant()->joint_positions()[1]);
  };
  df::State s = one_state(*rig.host, c);
  EXPECT_EQ(s.homed, 0);
  EXPECT_EQ(s.grip, 0);
  EXPECT_EQ(s.encoder[1], absolute() + kUnhomedOffsetCounts) << "relative: a fixed offset";
  EXPECT_EQ(rig.peer->leds(), df::kLedRed);
  c.homing = true;
  for (int i = 1; i < 20; ++i) EXPECT_EQ(one_state(*rig.host, c).homed, 0) << i;
  s = one_state(*rig.host, c);
  EXPECT_EQ(s.homed, 0x7) << "the twentieth packet with the homing bit";
  EXPECT_TRUE(rig.peer->homed());
  EXPECT_EQ(s.encoder[1], absolute());
  c.homing = false;
  c.leds = df::kLedGreen;
  s = one_state(*rig.host, c);
  EXPECT_EQ(s.homed, 0) << "homed only while each packet keeps the homing bit";
  EXPECT_FALSE(rig.peer->homed());
  EXPECT_EQ(s.encoder[1], absolute()) << "the counters stay zeroed at the index marks";
  EXPECT_EQ(rig.peer->leds(), df::kLedGreen);
}

TEST(FalconPeer, ADtrPulseStopsTheFirmwareAndItsMotors) {
  Rig rig;
  load_by_hand(*rig.host, 7914);
  df::Command push;
  push.motor = {100, 100, 100};
  one_state(*rig.host, push);
  ASSERT_TRUE(rig.peer->output_on());
  ASSERT_TRUE(rig.host->requests(df::bootloader_setup()));
  EXPECT_FALSE(rig.peer->firmware_running());
  EXPECT_FALSE(rig.peer->output_on());
  EXPECT_EQ(rig.peer->applied_force(), 0.0);
  EXPECT_TRUE(exchange(*rig.host, push).empty()) << "the bootloader reads no packets";
  EXPECT_EQ(rig.peer->chip().image_bytes(), 0u) << "the image is forgotten";
}

TEST(FalconPeer, ACorruptedPacketIsSentOnceWhenAsked) {
  Rig rig;
  load_by_hand(*rig.host, 7914);
  rig.peer->corrupt_next_packet();
  ASSERT_TRUE(rig.host->out(df::encode_command(df::Command{})));
  const auto bad = rig.host->data();
  ASSERT_EQ(bad.size(), df::kPacketBytes);
  df::Packet p;
  std::copy(bad.begin(), bad.end(), p.begin());
  df::State s;
  EXPECT_EQ(df::decode_state(p, s), df::PacketError::kBadNibble);
  one_state(*rig.host, df::Command{});
}

TEST(FalconPeer, AHungFirmwareTakesPacketsButAnswersNone) {
  Rig rig;
  load_by_hand(*rig.host, 7914);
  ASSERT_TRUE(rig.peer->inject(PeerFault::kStopAnswering));
  df::Command push;
  push.motor = {200, 0, 0};
  EXPECT_TRUE(exchange(*rig.host, push).empty());
  EXPECT_EQ(rig.peer->packets_taken(), 1u);
  EXPECT_EQ(rig.peer->packets_answered(), 0u);
  EXPECT_TRUE(rig.peer->output_on()) << "the motors keep what they were last sent";
}

TEST(FalconPeer, UnpluggedTheHostReadsEndOfFileAndNothingIsFelt) {
  Rig rig;
  load_by_hand(*rig.host, 7914);
  df::Command push;
  push.motor = {200, 0, 0};
  one_state(*rig.host, push);
  ASSERT_TRUE(rig.peer->inject(PeerFault::kTransportFault));
  EXPECT_EQ(rig.peer->applied_force(), 0.0);
  EXPECT_FALSE(rig.peer->output_on());
  std::array<unsigned char, 64> b{};
  std::string error;
  EXPECT_EQ(rig.host->read(b, 50, error), -1);
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(rig.host->write(df::encode_command(push), 10, error));
}

TEST(FalconPeer, TheFalconHasNoFaultReportNorSequenceNumbers) {
  Rig rig;
  EXPECT_FALSE(rig.peer->inject(PeerFault::kDeviceFault));
  EXPECT_FALSE(rig.peer->inject(PeerFault::kSkipSequence));
}

}  // namespace
}  // namespace hapticd::sim::falcon::testing
