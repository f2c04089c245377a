// `hapticd peer` in the kernel test machine, on the kernel's own interfaces: vcan and vxcan
// pass; slcan (a CAN controller's driver, can-dev's link kind "can", on a pseudo-terminal: the
// way a serial-line USB adapter appears) is refused without --impersonate-on-real-hardware and
// spoken on with it; a node that already answers at the configured id (heartbeats, only SDO
// replies, an ODrive's heartbeat, a second peer) is heard and refused; a gpio-sim chip passes
// and a sysfs device that is no GPIO chip is refused; the USB device controller here is
// dummy_hcd's. Real GPIO chips and UDCs: peer_guard_test.cpp feeds their facts.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <thread>

#include "gpio_sim_chip.h"
#include "process.h"
#include "pwm_sim.h"
#include "sim/peers/can/can_endpoint.h"
#include "sim/peers/gpio/gpio_endpoint.h"
#include "sim/peers/hid/hid_endpoint.h"
#include "slcan_tty.h"
#include "vcan_interface.h"

namespace hapticd::service {
namespace {

using hapticd::testing::example;
using hapticd::testing::has;

using hapticd::testing::ProcessResult;
using hapticd::testing::run_process;
using Kind = sim::EndpointVerdict::Kind;
using sim::CanLinkFacts;
using sim::judge_can_link;
using sim::kArphrdCan;
using sim::read_can_link;
using sim::gpio::GpioChipFacts;
using sim::gpio::read_gpio_chip;
using sim::hid::judge_hid_endpoint;
using sim::hid::read_udcs;
using sim::hid::UdcFacts;

ProcessResult peer(const std::string& config, const std::string& endpoint,
                   std::vector<std::string> more = {}) {
  std::vector<std::string> args = {HAPTICD_BINARY, "peer",   "--config",   example(config),
                                   "--endpoint",   endpoint, "--duration", "1",
                                   "--listen",     "0.5"};
  args.insert(args.end(), more.begin(), more.end());
  return run_process(args);
}

void ip(const std::string& args) {
  ASSERT_EQ(std::system(("ip " + args).c_str()), 0) << "ip " << args;
}

// A node on the bus, on its own thread: every `period` it sends `beat` (if its id is set),
// and it answers each frame with id `ask` with `answer` (if set).
class Node {
 public:
  Node(const kernel_test::VcanInterface& bus, can_frame beat, canid_t ask = 0,
       can_frame answer = {})
      : socket_(bus, {}), thread_([=, this] {
          auto next = std::chrono::steady_clock::now();
          while (!stop_.load()) {
            if (beat.can_id != 0 && std::chrono::steady_clock::now() >= next) {
              socket_.send(beat);
              next += std::chrono::milliseconds(100);
            }
            const auto got = socket_.receive(std::chrono::milliseconds(10));
            if (got && ask != 0 && got->frame.can_id == ask) {
              can_frame a = answer;
              socket_.send(a);
            }
          }
        }) {}
  ~Node() {
    stop_.store(true);
    thread_.join();
  }

 private:
  kernel_test::CanRawSocket socket_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

can_frame frame(canid_t id, std::initializer_list<std::uint8_t> data) {
  can_frame f{};
  f.can_id = id;
  f.len = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), f.data);
  return f;
}

TEST(PeerOnKernel, VcanIsASimulatedBusAndThePeerRunsOnIt) {
  kernel_test::VcanInterface bus("vcan0");
  const CanLinkFacts facts = read_can_link("vcan0");
  EXPECT_TRUE(facts.exists);
  EXPECT_EQ(facts.type, kArphrdCan);
  EXPECT_EQ(facts.kind, "vcan");
  const ProcessResult r = peer("can-cia402.yaml", "vcan0");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "vcan0 is a virtual CAN bus (vcan)")) << r.err;
  EXPECT_TRUE(has(r.out, "hapticd peer: can on vcan0")) << r.out;
}

TEST(PeerOnKernel, VxcanIsASimulatedBusToo) {
  ip("link add hkt-vx0 type vxcan peer name hkt-vx1");
  ip("link set hkt-vx0 up");
  ip("link set hkt-vx1 up");
  const CanLinkFacts facts = read_can_link("hkt-vx0");
  EXPECT_EQ(facts.type, kArphrdCan);
  EXPECT_EQ(facts.kind, "vxcan");
  const ProcessResult r = peer("can-cia402.yaml", "hkt-vx0");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  ip("link del hkt-vx0");
}

TEST(PeerOnKernel, ACanControllerIsRefusedUnlessTheFlagSaysToImpersonateThere) {
  Slcan slcan;
  ASSERT_FALSE(slcan.name().empty())
      << "no slcan interface: " << std::strerror(errno) << " (tools/kernel-vm/modules loads slcan)";
  const CanLinkFacts facts = read_can_link(slcan.name());
  EXPECT_EQ(facts.type, kArphrdCan);
  EXPECT_EQ(facts.kind, "can") << "can-dev's kind, as every controller's";
  EXPECT_EQ(judge_can_link(slcan.name(), facts).kind, Kind::kReal);

  const ProcessResult refused = peer("can-cia402.yaml", slcan.name());
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_TRUE(has(refused.err, slcan.name() + " is a CAN interface of link kind 'can'"))
      << refused.err;
  EXPECT_TRUE(has(refused.err, "--impersonate-on-real-hardware")) << refused.err;

  ip("link set " + slcan.name() + " type can bitrate 500000");
  ip("link set " + slcan.name() + " up");
  const ProcessResult told =
      peer("can-cia402.yaml", slcan.name(), {"--impersonate-on-real-hardware"});
  EXPECT_EQ(told.exit_code, 0) << told.err;
  EXPECT_TRUE(has(told.err, "impersonating a device on real hardware")) << told.err;
  // Its question to node 1 went out on the line: an SDO read of 0x1000.
  EXPECT_TRUE(has(slcan.written(), std::string("t601") + "8" + "4000100000000000"))
      << slcan.written();
}

TEST(PeerOnKernel, ANodeThatSendsHeartbeatsAtTheIdIsHeardAndRefused) {
  kernel_test::VcanInterface bus("vcan0");
  Node drive(bus, frame(0x701, {0x05}));
  const ProcessResult r = peer("can-cia402.yaml", "vcan0");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_TRUE(has(r.err,
                  "a node already answers at node id 1 on vcan0 (heard 0x701, the "
                  "heartbeat of node 1 (operational))"))
      << r.err;
  EXPECT_TRUE(r.out.empty()) << "no device was played: " << r.out;
}

TEST(PeerOnKernel, ASilentNodeIsHeardByItsAnswerToTheQuestion) {
  kernel_test::VcanInterface bus("vcan0");
  Node drive(bus, {}, 0x601, frame(0x581, {0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00}));
  const ProcessResult r = peer("can-cia402.yaml", "vcan0");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_TRUE(has(r.err, "heard 0x581, an SDO reply of node 1")) << r.err;
}

TEST(PeerOnKernel, AnOdriveAtTheIdIsHeardAndRefused) {
  kernel_test::VcanInterface bus("vcan0");
  Node axis(bus, frame(0x021, {0, 0, 0, 0, 1, 0, 0, 0}));
  const ProcessResult r = peer("can-odrive.yaml", "vcan0");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_TRUE(has(r.err, "heard 0x021, the heartbeat of ODrive node 1")) << r.err;
}

TEST(PeerOnKernel, ASecondPeerAtTheSameNodeIsRefusedAndAnotherNodeIsNot) {
  kernel_test::VcanInterface bus("vcan0");
  hapticd::testing::BackgroundProcess first({HAPTICD_BINARY, "peer", "--config",
                                             example("can-cia402.yaml"), "--endpoint", "vcan0",
                                             "--duration", "60", "--listen", "0.5"});
  // Until the first answers node 1's SDO, it is not there yet.
  kernel_test::CanRawOptions only_replies;
  only_replies.filters = {{0x581, CAN_SFF_MASK}};
  kernel_test::CanRawSocket asker(bus, only_replies);
  bool answered = false;
  for (int i = 0; i < 300 && !answered; ++i) {
    asker.send(frame(0x601, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));
    answered = asker.receive(std::chrono::milliseconds(100)).has_value();
  }
  ASSERT_TRUE(answered) << "the first peer never answered";
  const ProcessResult second = peer("can-cia402.yaml", "vcan0");
  EXPECT_EQ(second.exit_code, 4) << second.err;
  EXPECT_TRUE(has(second.err, "a node already answers at node id 1")) << second.err;
  const ProcessResult other = peer("can-cia402.yaml", "vcan0", {"--set", "device.can.node_id=2"});
  EXPECT_EQ(other.exit_code, 0) << other.err;
  first.signal(SIGTERM);
  EXPECT_EQ(first.wait().exit_code, 0);
}

TEST(PeerOnKernel, AGpioSimChipPassesAndASysfsDeviceThatIsNoChipIsRefused) {
  kernel_test::GpioSimChip chip(5);
  kernel_test::PwmSim pwm;
  const std::string dir =
      std::filesystem::canonical("/sys/bus/gpio/devices/" + chip.chip_name()).string();
  const GpioChipFacts facts = read_gpio_chip(dir);
  EXPECT_TRUE(facts.is_gpio_chip) << dir;
  EXPECT_EQ(facts.driver, "gpio-sim") << dir;
  const std::string channel = "/sys/devices/platform/hapticd-pwm-sim/channel0";
  const ProcessResult r = peer("gpio.yaml", dir + "," + channel);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "is a gpio-sim chip")) << r.err;

  const std::string not_chip = "/sys/devices/platform/hapticd-pwm-sim";
  const ProcessResult refused =
      peer("gpio.yaml", not_chip + "," + channel, {"--impersonate-on-real-hardware"});
  EXPECT_EQ(refused.exit_code, 4) << refused.err;
  EXPECT_TRUE(has(refused.err, "is not a GPIO chip's sysfs directory")) << refused.err;
}

TEST(PeerOnKernel, TheUsbDeviceControllerHereIsDummyHcdsSoAGadgetPasses) {
  const std::vector<UdcFacts> udcs = read_udcs();
  ASSERT_FALSE(udcs.empty()) << "dummy_hcd is loaded at boot";
  for (const UdcFacts& u : udcs) EXPECT_EQ(u.driver, "dummy_udc") << u.name;
  EXPECT_EQ(judge_hid_endpoint("/dev/raw-gadget", udcs).kind, Kind::kSimulated);
}

}  // namespace
}  // namespace hapticd::service
