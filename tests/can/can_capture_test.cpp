// A capture of the bus during a short run (this test's own CAN_RAW listener on vcan0, as
// candump would see it), decoded with the codecs into the sequence docs/drivers/can.md describes:
// start-up, the cyclic exchange, and the disable.
#include <gtest/gtest.h>

#include <sys/socket.h>

#include <algorithm>
#include <thread>

#include "can_rig.h"
#include "drivers/can/canopen.h"
#include "drivers/can/cia402.h"
#include "drivers/can/odrive_protocol.h"
#include "vcan_interface.h"

namespace hapticd::drivers::can::testing {
namespace {

using std::chrono::milliseconds;

// Runs `ticks` ticks of configure/enable/read+write/disable against the simulated drive on
// vcan0 and returns every frame a listener saw, in bus order.
std::vector<CanFrame> capture_run(const config::Config& cfg, int ticks, double force) {
  kernel_test::VcanInterface bus("vcan0");
  kernel_test::CanRawSocket listener(bus, {});
  // The capture is read after the run: room for all of it (a few hundred frames), or the
  // kernel drops the end of it as candump's default buffer would.
  const int room = 8 << 20;
  EXPECT_EQ(setsockopt(listener.fd(), SOL_SOCKET, SO_RCVBUFFORCE, &room, sizeof room), 0);
  auto peer = wiring::find_driver("can").peer.make_peer_on(cfg, "vcan0");
  sim::PeerRunner runner(*peer);
  auto device = wiring::find_driver("can").make_device(cfg);
  device->configure();
  device->enable();
  // Each tick waits for the drive's answer before the next, so the capture shows the
  // exchange itself, not how an emulated machine interleaves two of them.
  PositionSample s;
  for (int i = 0; i < ticks; ++i) {
    device->write(force);
    const auto end = std::chrono::steady_clock::now() + milliseconds(2000);
    while (device->read(s) == IoStatus::kNoNewData && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(milliseconds(1));
    }
  }
  device->disable();
  device->close();
  std::this_thread::sleep_for(milliseconds(50));
  runner.stop();
  std::vector<CanFrame> frames;
  while (const auto got = listener.receive(milliseconds(100))) {
    CanFrame f;
    f.rtr = (got->frame.can_id & CAN_RTR_FLAG) != 0;
    f.id = got->frame.can_id & CAN_SFF_MASK;
    f.len = got->frame.len;
    for (int i = 0; i < 8; ++i) f.data[i] = got->frame.data[i];
    frames.push_back(f);
  }
  return frames;
}

// Index of the first frame at or after `from` for which `match` holds; frames.size() if none.
template <typename M>
std::size_t find_from(const std::vector<CanFrame>& frames, std::size_t from, M match) {
  for (std::size_t i = from; i < frames.size(); ++i) {
    if (match(frames[i])) return i;
  }
  return frames.size();
}

// What a frame is in the cyclic exchange: a tick's command, the request that makes the drive
// answer (SYNC, an RTR), the answer, the first frame of the disable, or none of these.
enum class Role { kSkip, kCommand, kRequest, kAnswer, kDisable, kOther };

struct Cycles {
  std::size_t commands = 0, requests = 0, answers = 0;
  std::size_t end = 0;  // index of the disable's first frame, or frames.size()
};

// Walks the cyclic exchange from `from`: each command is followed by exactly one request before
// the next command, and each answer comes after its request. A starved guest may answer a
// tick's request only after the next tick's frames, so answers are counted, not placed.
template <typename Classify>
Cycles walk_cycles(const std::vector<CanFrame>& frames, std::size_t from, Classify role_of) {
  Cycles c;
  bool asked = true;
  for (c.end = from; c.end < frames.size(); ++c.end) {
    const CanFrame& f = frames[c.end];
    switch (role_of(f)) {
      case Role::kSkip:
        continue;
      case Role::kDisable:
        return c;
      case Role::kCommand:
        EXPECT_TRUE(asked) << "command " << c.commands << " came before the last one's request";
        asked = false;
        ++c.commands;
        break;
      case Role::kRequest:
        EXPECT_FALSE(asked) << "two requests for one command, at frame " << c.end;
        asked = true;
        ++c.requests;
        break;
      case Role::kAnswer:
        ++c.answers;
        EXPECT_LE(c.answers, c.requests) << "an answer before its request, at frame " << c.end;
        break;
      case Role::kOther:
        ADD_FAILURE() << "frame " << c.end << " (id " << f.id << ", " << int{f.len}
                      << " bytes) is not part of the cycle";
    }
  }
  return c;
}

// 60 ticks were asked for; an emulated guest overruns a few of them (missed ticks send
// nothing), so this asks for three quarters: the shape of each cycle is what is checked.
void expect_whole_cycles(const Cycles& c) {
  EXPECT_GE(c.commands, 45u);
  EXPECT_EQ(c.requests, c.commands);
  EXPECT_GE(c.answers + 1, c.requests) << "every request answered (the last may come late)";
}

std::optional<canopen::SdoRequest> sdo_write(const CanFrame& f, std::uint8_t node) {
  if (f.id != canopen::kSdoRxBase + node) return std::nullopt;
  const auto r = canopen::decode_sdo_request(f);
  if (r.kind != canopen::SdoRequest::Kind::kDownload) return std::nullopt;
  return r;
}

TEST(CanCapture, Cia402StartUpCyclicExchangeAndDisableAreWhatDesignSection6Says) {
  const config::Config cfg =
      load_example("can-cia402.yaml",
                   {"device.can.interface=vcan0", "device.can.sdo_timeout_ms=1000",
                    "device.can.state_timeout_ms=2000", "loop.rate_hz=100", "wall.stiffness=100",
                    "device.can.heartbeat_timeout_ms=1000"},
                   false);
  const std::vector<CanFrame> frames = capture_run(cfg, 60, 2.0);
  ASSERT_GT(frames.size(), 150u);
  const auto nmt = [](canopen::NmtCommand c) {
    return [c](const CanFrame& f) { return canopen::decode_nmt(f, 1) == c; };
  };
  const auto write_of = [](std::uint16_t index, std::uint8_t sub, std::uint32_t value) {
    return [=](const CanFrame& f) {
      const auto r = sdo_write(f, 1);
      return r && r->at.index == index && r->at.subindex == sub && r->value == value;
    };
  };
  // Start-up: pre-operational, output off, the parameters, NMT start, the state machine.
  const std::size_t preop = find_from(frames, 0, nmt(canopen::NmtCommand::kEnterPreOperational));
  EXPECT_EQ(preop, 0u) << "the first frame puts the drive in pre-operational";
  const std::size_t off = find_from(frames, preop, write_of(0x6040, 0, 0x00));
  const std::size_t mode = find_from(frames, off, write_of(0x6060, 0, 10));
  // 0x1006: the 100 Hz cycle of this run, in us.
  const std::size_t cycle = find_from(frames, mode, write_of(0x1006, 0, 10000));
  const std::size_t producer = find_from(frames, cycle, write_of(0x1017, 0, 100));
  const std::size_t mapped = find_from(frames, producer, write_of(0x1A00, 2, 0x60640020));
  const std::size_t consumer = find_from(frames, mapped, write_of(0x1016, 1, 0x007F0064));
  const std::size_t start = find_from(frames, consumer, nmt(canopen::NmtCommand::kStart));
  const std::size_t cw6 = find_from(frames, start, write_of(0x6040, 0, 0x06));
  const std::size_t cw7 = find_from(frames, cw6, write_of(0x6040, 0, 0x07));
  const std::size_t cwf = find_from(frames, cw7, write_of(0x6040, 0, 0x0F));
  ASSERT_LT(cwf, frames.size()) << "controlword 0x00, mode 10, 0x1006, 0x1017, mapping, 0x1016, "
                                   "NMT start, 0x06, 0x07, 0x0F in that order";
  // Every SDO request was answered by the drive (0x581), none aborted.
  std::size_t requests = 0;
  std::size_t answers = 0;
  for (std::size_t i = 0; i <= cwf + 1 && i < frames.size(); ++i) {
    requests += frames[i].id == 0x601 ? 1 : 0;
    answers += frames[i].id == 0x581 && frames[i].data[0] != 0x80 ? 1 : 0;
  }
  EXPECT_EQ(requests, answers);
  EXPECT_TRUE(
      std::all_of(frames.begin(), frames.begin() + static_cast<long>(cwf),
                  [](const CanFrame& f) { return f.id != 0x201 && f.id != canopen::kSyncId; }))
      << "no PDO and no SYNC before operation is enabled";
  // Cyclic: RPDO (controlword 0x0F, target torque) then SYNC, each SYNC answered by TPDO1.
  // (heartbeats, the drive's and hapticd's, come in between at their own rate: left out here)
  std::vector<CanFrame> cyclic;
  for (std::size_t k = cwf; k < frames.size(); ++k) {
    if (frames[k].id != 0x701 && frames[k].id != 0x77F) cyclic.push_back(frames[k]);
  }
  const std::size_t first = find_from(cyclic, 0, [](const CanFrame& f) { return f.id == 0x201; });
  const Cycles c = walk_cycles(cyclic, first, [](const CanFrame& f) {
    if (f.id == canopen::kSyncId) return Role::kRequest;
    if (f.id == 0x181u) {
      EXPECT_TRUE(canopen::decode_tpdo1(f)) << "TPDO1: statusword and position";
      return Role::kAnswer;
    }
    const auto rpdo = canopen::decode_rpdo1(f);
    if (f.id != 0x201 || !rpdo) return Role::kOther;
    if (rpdo->target_torque == 0) return Role::kDisable;
    EXPECT_EQ(rpdo->controlword, cia402::kCwEnableOperation);
    EXPECT_EQ(rpdo->target_torque, 40) << "2 N through 10 mm is 40 per mille of 0.5 N m";
    return Role::kCommand;
  });
  expect_whole_cycles(c);
  const std::size_t i = c.end;
  // Disable: zero torque, controlword 0x06, NMT pre-operational.
  const std::size_t zero = find_from(cyclic, i, [](const CanFrame& f) {
    const auto r = canopen::decode_rpdo1(f);
    return f.id == 0x201 && r && r->target_torque == 0;
  });
  const std::size_t shutdown = find_from(cyclic, zero, [](const CanFrame& f) {
    const auto r = canopen::decode_rpdo1(f);
    return f.id == 0x201 && r && r->controlword == cia402::kCwShutdown;
  });
  const std::size_t preop_end =
      find_from(cyclic, shutdown, nmt(canopen::NmtCommand::kEnterPreOperational));
  std::string tail;
  for (std::size_t k = cyclic.size() > 12 ? cyclic.size() - 12 : 0; k < cyclic.size(); ++k) {
    tail += " " + std::to_string(cyclic[k].id) + "/" + std::to_string(cyclic[k].len);
  }
  EXPECT_LT(preop_end, cyclic.size()) << "torque 0, then 0x06, then NMT pre-operational; the "
                                         "capture ends with (id/len):"
                                      << tail;
}

TEST(CanCapture, OdriveStartUpCyclicExchangeAndDisable) {
  const config::Config cfg = load_example(
      "can-odrive.yaml",
      {"device.can.interface=vcan0", "device.can.sdo_timeout_ms=1000",
       "device.can.state_timeout_ms=2000", "loop.rate_hz=100", "wall.stiffness=100",
       "device.can.heartbeat_timeout_ms=1000", "device.can.odrive.watchdog_timeout_s=1"},
      false);
  const std::vector<CanFrame> frames = capture_run(cfg, 60, 2.0);
  const auto cmd = [](std::uint8_t c, bool rtr) {
    return [=](const CanFrame& f) { return f.id == odrive::frame_id(1, c) && f.rtr == rtr; };
  };
  const std::size_t version = find_from(frames, 0, cmd(odrive::kGetVersion, true));
  ASSERT_LT(version, frames.size());
  std::string before;
  for (std::size_t k = 0; k < version; ++k) {
    before += " " + std::to_string(frames[k].id) + (frames[k].rtr ? "r" : "") + "/" +
              std::to_string(frames[k].len);
  }
  // The watchdog feeder starts before anything else (a 0.5 axis' watchdog counts from power-on),
  // so its heartbeat requests may come first, racing Get_Version from their own thread.
  EXPECT_TRUE(std::all_of(frames.begin(), frames.begin() + static_cast<long>(version),
                          [&](const CanFrame& f) {
                            return cmd(odrive::kHeartbeat, false)(f) ||
                                   cmd(odrive::kHeartbeat, true)(f);
                          }))
      << "Get_Version is hapticd's first frame but for the watchdog feeder's heartbeat requests "
         "(firmware auto); only those and the axis' heartbeats before; before it came (id/len):"
      << before;
  const std::size_t answer = find_from(frames, version, cmd(odrive::kGetVersion, false));
  const std::size_t idle = find_from(frames, answer, [](const CanFrame& f) {
    return f.id == odrive::frame_id(1, odrive::kSetAxisState) && get_u32(f, 0) == 1;
  });
  const std::size_t mode = find_from(frames, idle, [](const CanFrame& f) {
    return f.id == odrive::frame_id(1, odrive::kSetControllerMode) && get_u32(f, 0) == 1 &&
           get_u32(f, 4) == 1;
  });
  const std::size_t closed = find_from(frames, mode, [](const CanFrame& f) {
    return f.id == odrive::frame_id(1, odrive::kSetAxisState) && get_u32(f, 0) == 8;
  });
  ASSERT_LT(closed, frames.size()) << "Get_Version, IDLE, torque + passthrough, CLOSED_LOOP";
  // Each tick: Set_Input_Torque, the RTR for the estimates, the drive's answer; the axis'
  // heartbeats come on their own clock, between any two frames.
  const std::size_t first = find_from(frames, closed, cmd(odrive::kSetInputTorque, false));
  const Cycles c = walk_cycles(frames, first, [&](const CanFrame& f) {
    if (cmd(odrive::kHeartbeat, false)(f)) return Role::kSkip;
    if (cmd(odrive::kGetEncoderEstimates, true)(f)) return Role::kRequest;
    if (cmd(odrive::kGetEncoderEstimates, false)(f)) {
      EXPECT_TRUE(odrive::decode_encoder_estimates(f));
      return Role::kAnswer;
    }
    if (!cmd(odrive::kSetInputTorque, false)(f)) return Role::kOther;
    if (get_f32(f, 0) == 0.0f) return Role::kDisable;
    EXPECT_FLOAT_EQ(get_f32(f, 0), 2.0f * 0.015625f);
    return Role::kCommand;
  });
  expect_whole_cycles(c);
  const std::size_t i = c.end;
  const std::size_t back = find_from(frames, i, [](const CanFrame& f) {
    return f.id == odrive::frame_id(1, odrive::kSetAxisState) && get_u32(f, 0) == 1;
  });
  EXPECT_LT(back, frames.size()) << "disable: torque 0, then IDLE";
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
