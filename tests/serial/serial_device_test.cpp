// The serial Device on one end of a socketpair, the test reading and writing the device's
// bytes on the other: the request exchange asks while output is off and answers come back as
// positions of every joint; the stop frame (zero force, enable off) goes out on disable and from
// the crash handler's emergency stop, on the descriptor already open; a device that stops
// reading faults after out_full_fault ticks.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <string_view>
#include <vector>

#include "drivers/io/unique_fd.h"
#include "drivers/serial/serial_device.h"

namespace hapticd::drivers::serial {
namespace {

// A two-joint board: [0xA5, i16 pos0, i16 pos1, sum8] in, [0x5A, flags, i16 f0, i16 f1] out.
std::shared_ptr<SerialSettings> board(Exchange exchange) {
  auto s = std::make_shared<SerialSettings>();
  s->port = "socketpair";
  s->exchange = exchange;
  s->answer_timeout_ms = 200;
  s->out_full_fault = 3;
  s->input.shape = {
      {0xA5}, 6, FrameCheck{find_check_algorithm("sum8"), 5, 1, 5, field::Endian::kLittle}};
  s->input.positions = {field::typed(field::FieldType::kI16, 1, field::Endian::kLittle, 1e-3),
                        field::typed(field::FieldType::kI16, 3, field::Endian::kLittle, 1e-3)};
  s->output.shape = {{0x5A}, 6, std::nullopt};
  s->output.forces = {field::typed(field::FieldType::kI16, 2, field::Endian::kLittle, 1e-3),
                      field::typed(field::FieldType::kI16, 4, field::Endian::kLittle, 1e-3)};
  s->output.enable = EnableField{field::FieldSpec{1, 0, 1}, 1.0, 0.0};
  return s;
}

struct Rig {
  std::shared_ptr<SerialSettings> s;
  io::UniqueFd mine;
  std::unique_ptr<SerialDevice> device;
  explicit Rig(Exchange e) : s(board(e)) {
    auto [a, b] = io::seqpacket_pair();
    mine = std::move(b);
    auto end = std::make_shared<io::UniqueFd>(std::move(a));
    device = std::make_unique<SerialDevice>(
        s,
        [end] {
          return Port{std::move(*end), false, {}};
        },
        1e-3, 2);
  }
  // The device's answer: positions in mm.
  void answer(std::int16_t p0, std::int16_t p1) {
    std::array<std::uint8_t, 6> f{0xA5,
                                  static_cast<std::uint8_t>(p0),
                                  static_cast<std::uint8_t>(p0 >> 8),
                                  static_cast<std::uint8_t>(p1),
                                  static_cast<std::uint8_t>(p1 >> 8),
                                  0};
    for (int i = 1; i < 5; ++i) f[5] = static_cast<std::uint8_t>(f[5] + f[i]);
    ASSERT_EQ(::send(mine.get(), f.data(), f.size(), 0), 6);
  }
  // Every frame the driver sent so far.
  std::vector<std::array<std::uint8_t, 6>> sent() {
    std::vector<std::array<std::uint8_t, 6>> out;
    std::array<std::uint8_t, 6> f{};
    while (::recv(mine.get(), f.data(), f.size(), MSG_DONTWAIT) == 6) out.push_back(f);
    return out;
  }
};

TEST(SerialDevice, RequestsWhileOffAndReadsEveryJoint) {
  Rig rig(Exchange::kRequest);
  rig.answer(10, -20);  // the answer configure waits for
  rig.device->configure();
  EXPECT_EQ(rig.device->info().joints, 2u);
  auto sent = rig.sent();
  ASSERT_GE(sent.size(), 1u) << "configure asked";
  EXPECT_EQ(sent.back()[1], 0) << "enable bit off while output is off";
  rig.answer(11, -21);
  std::array<PositionSample, 2> s{};
  ASSERT_EQ(rig.device->read(s), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(s[0].position, 0.011);
  EXPECT_DOUBLE_EQ(s[1].position, -0.021);
  EXPECT_EQ(rig.sent().size(), 1u) << "the read asked for the next answer";
  rig.device->enable();
  rig.sent();
  const std::array<double, 2> f{0.5, -0.25};
  ASSERT_EQ(rig.device->write(f), IoStatus::kOk);
  sent = rig.sent();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0][1], 1) << "enabled";
  EXPECT_EQ(static_cast<std::int16_t>(sent[0][2] | sent[0][3] << 8), 500);
  EXPECT_EQ(static_cast<std::int16_t>(sent[0][4] | sent[0][5] << 8), -250);
  ASSERT_EQ(rig.device->read(s), IoStatus::kNoNewData) << "no answer yet: no request either";
  EXPECT_TRUE(rig.sent().empty()) << "output on: the force frame is the request";
}

TEST(SerialDevice, TheStopFrameGoesOutOnDisableAndFromTheEmergencyStop) {
  Rig rig(Exchange::kStream);
  rig.answer(0, 0);
  rig.device->configure();
  rig.device->enable();
  const std::array<double, 2> f{1.0, 1.0};
  ASSERT_EQ(rig.device->write(f), IoStatus::kOk);
  rig.sent();
  rig.device->emergency_stop();  // what the crash handler does: one write(2), nothing else
  auto sent = rig.sent();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0], (std::array<std::uint8_t, 6>{0x5A, 0, 0, 0, 0, 0}))
      << "zero force, enable off";
  rig.device->disable();
  sent = rig.sent();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0], (std::array<std::uint8_t, 6>{0x5A, 0, 0, 0, 0, 0}));
}

TEST(SerialDevice, ADeviceThatStopsReadingFaultsAfterOutFullFaultTicks) {
  Rig rig(Exchange::kStream);
  rig.answer(0, 0);
  rig.device->configure();
  rig.device->enable();
  const std::array<double, 2> f{0.1, 0.1};
  IoStatus st = IoStatus::kOk;
  int ticks = 0;
  for (; ticks < 100000 && st == IoStatus::kOk; ++ticks) st = rig.device->write(f);  // never read
  EXPECT_EQ(st, IoStatus::kTransportFault);
  EXPECT_NE(rig.device->describe_fault().find("took no whole frame for 3 ticks"), std::string::npos)
      << rig.device->describe_fault();
}

std::uint64_t counter(const Device& d, std::string_view name) {
  for (const base::Counter& c : d.counters()) {
    if (c.name() == name) return c.value();
  }
  return 0;
}

// A device that floods: a tick reads 2 KB and drops the rest, counted, so the tick's work is
// bounded whatever arrives; the next tick starts on what comes next.
TEST(SerialDevice, AFloodIsReadUpToItsBoundAndTheRestDroppedAndCounted) {
  Rig rig(Exchange::kStream);
  rig.answer(0, 0);
  rig.device->configure();
  rig.device->enable();
  // A socketpair counts each message's overhead against its buffer: widen it (or setsockopt's
  // ordinary limit, for a test not run as root).
  const int big = 8 << 20;
  if (::setsockopt(rig.mine.get(), SOL_SOCKET, SO_SNDBUFFORCE, &big, sizeof big) != 0) {
    ::setsockopt(rig.mine.get(), SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
  }
  std::array<std::uint8_t, 6> f{0xA5, 1, 0, 0, 0, 1};
  int sent = 0;
  while (sent < 2000 && ::send(rig.mine.get(), f.data(), f.size(), MSG_DONTWAIT) == 6) ++sent;
  ASSERT_GT(sent * 6, 2048 + 600) << "more than a tick's bound waiting";
  std::array<PositionSample, 2> s{};
  ASSERT_EQ(rig.device->read(s), IoStatus::kOk);
  const std::uint64_t frames = counter(*rig.device, "frames");
  EXPECT_LE(frames, 1u + 2048 / 6 + 1) << "no more than the bound was scanned";
  EXPECT_GT(counter(*rig.device, "backlog_bytes"), 3000u) << "the rest dropped and counted";
  rig.answer(1234, -1);
  ASSERT_EQ(rig.device->read(s), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(s[0].position, 1.234) << "the next frame whole";
}

}  // namespace
}  // namespace hapticd::drivers::serial
