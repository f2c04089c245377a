// What a broken device or simulated device can hand the driver: messages on the loopback that
// are no event, values at the limits of int, SYN_DROPPED storms, events of codes it does not
// know, more events in a tick than it drains. Each is counted or used, and the RT path
// allocates nothing meanwhile.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <climits>
#include <cstring>
#include <string_view>
#include <thread>

#include "alloc_counter.h"
#include "device_counter.h"
#include "drivers/evdev/evdev_device.h"
#include "drivers/evdev/socket_transport.h"
#include "fake_transport.h"

namespace hapticd::drivers::evdev {
namespace {

using hapticd::testing::counter_value;

using Bytes = std::vector<std::uint8_t>;

void send(int fd, const Bytes& b) {
  ASSERT_EQ(::send(fd, b.data(), b.size(), 0), static_cast<ssize_t>(b.size()));
}

TEST(EvdevMalformed, LoopbackMessagesThatAreNoEventAreSkippedWithoutAllocating) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
  SocketTransport t{io::UniqueFd(fds[0]), std::chrono::milliseconds(100)};
  const io::UniqueFd peer{fds[1]};
  send(peer.get(), {0x77, 1, 2});    // no message type
  send(peer.get(), {1, 3, 0});       // an event cut short
  send(peer.get(), Bytes(3000, 1));  // longer than any message
  wire::Message facts;               // a message only a query is answered with, whose
  facts.type = wire::Type::kFacts;   // strings would be allocated
  facts.facts.name = std::string(255, 'x');
  Bytes bytes;
  wire::encode(facts, bytes);
  send(peer.get(), bytes);
  Bytes event(32);
  event.resize(wire::encode_event({kEvAbs, 0, INT_MIN, 7}, event));
  send(peer.get(), event);
  wire::Event ev;
  int error = 0, malformed = 0;
  ReadStatus r = ReadStatus::kMalformed;
  const hapticd::testing::AllocationScope scope;
  for (int i = 0; i < 10 && r == ReadStatus::kMalformed; ++i) {
    r = t.read(ev, error);
    if (r == ReadStatus::kMalformed) ++malformed;
  }
  EXPECT_EQ(scope.count(), 0u) << "allocations reading what the simulated device sent";
  ASSERT_EQ(r, ReadStatus::kEvent);
  EXPECT_EQ(ev.value, INT_MIN);
  EXPECT_EQ(malformed, 4);
  EXPECT_EQ(t.read(ev, error), ReadStatus::kEmpty);
}

// The simulated device's end of the transport: what the driver sent, and the descriptor it
// answers updates on (kAnswers, handed over with SCM_RIGHTS when the transport is made).
struct DeviceEnd {
  explicit DeviceEnd(int fd) : main(fd) {
    std::uint8_t type = 0;
    iovec iov{&type, 1};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    EXPECT_EQ(::recvmsg(fd, &msg, MSG_CMSG_CLOEXEC), 1);
    EXPECT_EQ(type, static_cast<std::uint8_t>(wire::Type::kAnswers));
    const cmsghdr* c = CMSG_FIRSTHDR(&msg);
    EXPECT_NE(c, nullptr);
    int passed = -1;
    if (c != nullptr) std::memcpy(&passed, CMSG_DATA(c), sizeof passed);
    answers.reset(passed);
  }
  void status(int fd, int error) {
    wire::Message m;
    m.type = wire::Type::kStatus;
    m.error = error;
    Bytes b;
    wire::encode(m, b);
    send(fd, b);
  }
  io::UniqueFd main, answers;
};

// EVIOCSFF returns once the device has taken the update, with its answer: over the loopback the
// update waits for that answer on a socket of its own, so the events the RT thread reads meanwhile
// are left where they are, and a request (EVIOCGRAB) still takes its own answer, not an update's.
TEST(EvdevMalformed, AnUpdateWaitsForItsAnswerOnItsOwnSocketAndRequestsTakeTheirOwn) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
  SocketTransport t{io::UniqueFd(fds[0]), std::chrono::milliseconds(300)};
  DeviceEnd dev(fds[1]);
  ASSERT_TRUE(dev.answers);
  Bytes event(32);
  event.resize(wire::encode_event({kEvAbs, 0, 42, 7}, event));
  send(dev.main.get(), event);
  const auto t0 = std::chrono::steady_clock::now();
  std::thread late([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    dev.status(dev.answers.get(), EIO);
  });
  EXPECT_EQ(t.update({0, 0x4000, 100, 0}), EIO) << "the device's answer, whenever it comes";
  late.join();
  EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(60));
  wire::Event ev;
  int error = 0;
  ASSERT_EQ(t.read(ev, error), ReadStatus::kEvent) << "the event is still the RT thread's";
  EXPECT_EQ(ev.value, 42);
  dev.status(dev.main.get(), EBUSY);  // the grab's answer: held elsewhere
  try {
    t.grab(true);
    ADD_FAILURE() << "the grab took no answer";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("another process has grabbed"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(t.update({0, 0x4000, 100, 0}), ETIMEDOUT) << "no answer within the time-out";
  dev.answers.reset();
  EXPECT_EQ(t.update({0, 0x4000, 100, 0}), ENODEV) << "the device gone";
  EXPECT_EQ(t.read(ev, error), ReadStatus::kEmpty) << "no answer left over for a later tick";
}

struct Hostile {
  Hostile() {
    auto s = std::make_shared<EvdevSettings>();
    s->select.name = "x";
    s->axis = {0, Scale::kRange, -0.05, 0.05, false, 0.0};
    s->force_full_scale = 10.0;
    script->facts.name = "hostile";
    script->facts.has_axis = true;
    script->facts.range = {INT_MIN, INT_MAX, 0};
    script->facts.ff_constant = script->facts.ff_gain = script->facts.ff_autocenter = true;
    script->facts.ff_effects = 1;
    device = std::make_unique<EvdevDevice>(
        s,
        [sc = script] {
          EvdevDevice::Opened o;
          o.transport = std::make_unique<testing::FakeTransport>(sc);
          return o;
        },
        0.001);
  }
  void event(ReadStatus st, int type, int code, int value, std::int64_t t = 1) {
    script->events.push_back(
        {st, {static_cast<std::uint16_t>(type), static_cast<std::uint16_t>(code), value, t}});
  }
  std::shared_ptr<testing::Script> script = std::make_shared<testing::Script>();
  std::unique_ptr<EvdevDevice> device;
};

TEST(EvdevMalformed, AHostileEventStreamIsCountedAndReadWithoutAllocating) {
  Hostile h;
  h.device->configure();
  h.device->enable();
  h.script->levels.reserve(64);  // the fake's own record of updates: not the driver's
  h.script->directions.reserve(64);
  for (int i = 0; i < 100; ++i) h.event(ReadStatus::kDropped, kEvSyn, kSynDropped, 0);
  h.event(ReadStatus::kEvent, kEvAbs, 0x3f, 5);                   // an axis it does not use
  h.event(ReadStatus::kEvent, 0x1f, 0xffff, -1);                  // no event type at all
  h.event(ReadStatus::kEvent, kEvFfStatus, 9, kFfStatusStopped);  // not hapticd's effect
  h.event(ReadStatus::kMalformed, 0, 0, 0);
  h.event(ReadStatus::kEvent, kEvAbs, 0, INT_MAX, 5);
  h.event(ReadStatus::kEvent, kEvSyn, kSynReport, 0, 5);
  PositionSample s;
  IoStatus read = IoStatus::kOk, written = IoStatus::kOk;
  {
    const hapticd::testing::AllocationScope scope;
    read = h.device->read(s);
    written = h.device->write(25.0);  // beyond full scale: the level's limit
    EXPECT_EQ(scope.count(), 0u);
  }
  h.device->wait_output();
  ASSERT_EQ(read, IoStatus::kOk);
  EXPECT_DOUBLE_EQ(s.position, 0.05) << "INT_MAX is the range's maximum";
  EXPECT_EQ(written, IoStatus::kOk);
  EXPECT_EQ(h.script->levels.back(), kLevelMax);
  EXPECT_EQ(counter_value(*h.device, "syn_dropped"), 100u);
  EXPECT_EQ(counter_value(*h.device, "other_events"), 3u);
  EXPECT_EQ(counter_value(*h.device, "malformed_messages"), 1u);
  EXPECT_EQ(counter_value(*h.device, "axis_events"), 1u);
}

TEST(EvdevMalformed, AFloodIsDrainedAtTheBoundAndTheRestReadNextTick) {
  Hostile h;
  h.device->configure();
  h.device->enable();
  for (int i = 0; i < 400; ++i) {  // 800 events: 512 in the first tick, 288 in the second
    h.event(ReadStatus::kEvent, kEvAbs, 0, i, i + 1);
    h.event(ReadStatus::kEvent, kEvSyn, kSynReport, 0, i + 1);
  }
  PositionSample s;
  const hapticd::testing::AllocationScope scope;
  ASSERT_EQ(h.device->read(s), IoStatus::kOk);
  EXPECT_EQ(s.samples, 256u);
  EXPECT_EQ(s.time_ns, 256);
  ASSERT_EQ(h.device->read(s), IoStatus::kOk);
  EXPECT_EQ(s.samples, 144u);
  EXPECT_EQ(s.time_ns, 400);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(counter_value(*h.device, "drain_limit"), 1u);
  EXPECT_EQ(counter_value(*h.device, "superseded"), 398u);
}

// libevdev's complaints (an invalid slot, a double tracking id, a reader not keeping up after
// SYN_DROPPED) cannot be printed on the RT thread: they show as the driver's counter.
TEST(EvdevMalformed, WhatLibevdevLoggedIsTheDriversCounter) {
  Hostile h;
  h.device->configure();
  h.device->enable();
  h.script->library_messages = 2;
  PositionSample s;
  ASSERT_EQ(h.device->read(s), IoStatus::kOk);
  EXPECT_EQ(counter_value(*h.device, "library_messages"), 2u);
}

}  // namespace
}  // namespace hapticd::drivers::evdev
