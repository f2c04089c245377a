// `hapticd peer` refuses to play a device on real hardware unless told so, and on CAN at a
// node id that already answers: the decisions fed the facts the kernel would report (real
// hardware included, which no test machine has), the sysfs readers on trees laid out as the
// kernel lays them out, and the whole check on a GPIO chip of another driver.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "config/config_loader.h"
#include "drivers/device.h"
#include "process.h"
#include "service/commands/peer_endpoint.h"
#include "service/config_source.h"
#include "sim/peers/endpoint_verdict.h"
#include "wiring/registry.h"
#if HAPTICD_WITH_CAN
#include "sim/peers/can/can_endpoint.h"
#include "sim/peers/can/can_node_listen.h"
#endif
#if HAPTICD_WITH_GPIO
#include "sim/peers/gpio/gpio_endpoint.h"
#endif
#if HAPTICD_WITH_HID
#include "sim/peers/hid/hid_endpoint.h"
#endif

namespace hapticd::service {
namespace {

using hapticd::testing::has;

namespace fs = std::filesystem;
using sim::EndpointVerdict;
using Kind = EndpointVerdict::Kind;

#if HAPTICD_WITH_CAN
using sim::CanLinkFacts;
using sim::judge_can_link;
using sim::kArphrdCan;
using sim::read_can_link;

TEST(PeerGuard, OnlyVcanAndVxcanAreSimulatedCanBuses) {
  EXPECT_EQ(judge_can_link("vcan0", {true, kArphrdCan, "vcan"}).kind, Kind::kSimulated);
  EXPECT_EQ(judge_can_link("vxcan1", {true, kArphrdCan, "vxcan"}).kind, Kind::kSimulated);
  // A controller's driver registers through can-dev (kind "can"): a USB adapter, slcan, a
  // SoC's controller, an SPI MCP2515 alike.
  const EndpointVerdict real = judge_can_link("can0", {true, kArphrdCan, "can"});
  EXPECT_EQ(real.kind, Kind::kReal);
  EXPECT_TRUE(has(real.what, "can0") && has(real.what, "'can'")) << real.what;
  EXPECT_EQ(judge_can_link("can1", {true, kArphrdCan, ""}).kind, Kind::kReal)
      << "a CAN link of no kind is not known to be virtual";
  EXPECT_EQ(judge_can_link("can2", {true, kArphrdCan, "vcanx"}).kind, Kind::kReal);
}

TEST(PeerGuard, WhatIsNotACanInterfaceIsRefusedFlagOrNot) {
  const EndpointVerdict none = judge_can_link("can9", {});
  EXPECT_EQ(none.kind, Kind::kUnusable);
  EXPECT_TRUE(has(none.what, "no network interface 'can9'")) << none.what;
  const EndpointVerdict eth = judge_can_link("eth0", {true, 1, ""});
  EXPECT_EQ(eth.kind, Kind::kUnusable);
  EXPECT_TRUE(has(eth.what, "not a CAN interface (link type 1")) << eth.what;
}

TEST(PeerGuard, ReadsTheLinkKindFromTheKernel) {
  // This machine's loopback interface, through rtnetlink: not CAN, so unusable.
  const CanLinkFacts lo = read_can_link("lo");
  ASSERT_TRUE(lo.exists);
  EXPECT_EQ(lo.type, 772u) << "ARPHRD_LOOPBACK";
  EXPECT_EQ(judge_can_link("lo", lo).kind, Kind::kUnusable);
  EXPECT_FALSE(read_can_link("hapticd-none0").exists);
  EXPECT_FALSE(read_can_link(std::string(40, 'x')).exists) << "longer than any interface name";
}

#endif

#if HAPTICD_WITH_GPIO
using sim::gpio::GpioChipFacts;
using sim::gpio::judge_gpio_chip;
using sim::gpio::read_gpio_chip;

TEST(PeerGuard, OnlyGpioSimIsASimulatedGpioChip) {
  EXPECT_EQ(judge_gpio_chip("/sys/x/gpiochip1", {true, true, "gpio-sim"}).kind, Kind::kSimulated);
  const EndpointVerdict real = judge_gpio_chip("/sys/devices/platform/soc/fe200000.gpio/gpiochip0",
                                               {true, true, "pinctrl-bcm2835"});
  EXPECT_EQ(real.kind, Kind::kReal);
  EXPECT_TRUE(has(real.what, "driver 'pinctrl-bcm2835', not gpio-sim")) << real.what;
  EXPECT_EQ(judge_gpio_chip("/sys/x/gpiochip2", {true, true, ""}).kind, Kind::kReal);
  // A directory that is not a chip: the peer would write "pull-up" into whatever is there.
  EXPECT_EQ(judge_gpio_chip("/tmp/x", {true, false, ""}).kind, Kind::kUnusable);
  EXPECT_EQ(judge_gpio_chip("/tmp/none", {}).kind, Kind::kUnusable);
}

#endif

#if HAPTICD_WITH_HID
using sim::hid::judge_hid_endpoint;
using sim::hid::read_udcs;
using sim::hid::UdcFacts;

TEST(PeerGuard, AGadgetNeedsEveryControllerToBeDummyUdcAndUhidNeedsNone) {
  const std::vector<UdcFacts> dummy = {{"dummy_udc.0", "dummy_udc"}};
  const std::vector<UdcFacts> board = {{"fe980000.usb", "dwc2"}};
  const std::vector<UdcFacts> both = {{"dummy_udc.0", "dummy_udc"}, {"fe980000.usb", "dwc2"}};
  EXPECT_EQ(judge_hid_endpoint("/dev/raw-gadget", dummy).kind, Kind::kSimulated);
  EXPECT_EQ(judge_hid_endpoint("/dev/hidg0", dummy).kind, Kind::kSimulated);
  const EndpointVerdict real = judge_hid_endpoint("/dev/raw-gadget", board);
  EXPECT_EQ(real.kind, Kind::kReal);
  EXPECT_TRUE(has(real.what, "fe980000.usb (driver 'dwc2')")) << real.what;
  EXPECT_EQ(judge_hid_endpoint("/dev/hidg0", both).kind, Kind::kReal)
      << "which controller a gadget lands on is not the peer's to choose";
  EXPECT_EQ(judge_hid_endpoint("/dev/raw-gadget", {}).kind, Kind::kUnusable);
  EXPECT_EQ(judge_hid_endpoint("/dev/uhid", board).kind, Kind::kSimulated)
      << "uhid makes a device on this host only";
}

#endif

#if HAPTICD_WITH_GPIO
// A sysfs-like tree: DIR/devices/platform/NAME.0/gpiochip3 on bus gpio, NAME.0 bound to
// driver NAME; a UDC class directory the same way.
struct FakeSysfs {
  explicit FakeSysfs(const std::string& driver) {
    static int counter = 0;
    root = fs::temp_directory_path() /
           ("hapticd-peer-guard-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
    fs::remove_all(root);
    const fs::path parent = root / "devices/platform" / (driver + ".0");
    chip = parent / "gpiochip3";
    fs::create_directories(chip);
    fs::create_directories(root / "bus/gpio");
    fs::create_directories(root / "bus/platform/drivers" / driver);
    fs::create_symlink(root / "bus/gpio", chip / "subsystem");
    fs::create_symlink(root / "bus/platform/drivers" / driver, parent / "driver");
    fs::create_directories(root / "class/udc");
    fs::create_directory_symlink(parent, root / "class/udc" / (driver + ".0"));
    fs::create_symlink(parent, parent / "device");
  }
  ~FakeSysfs() { fs::remove_all(root); }
  fs::path root, chip;
};

TEST(PeerGuard, ReadsAChipsBusAndDriverAndEachControllersDriverFromSysfs) {
  FakeSysfs sys("pinctrl-bcm2835");
  const GpioChipFacts f = read_gpio_chip(sys.chip.string());
  EXPECT_TRUE(f.exists);
  EXPECT_TRUE(f.is_gpio_chip);
  EXPECT_EQ(f.driver, "pinctrl-bcm2835");
  const GpioChipFacts parent = read_gpio_chip(sys.chip.parent_path().string());
  EXPECT_TRUE(parent.exists);
  EXPECT_FALSE(parent.is_gpio_chip) << "the platform device is not the chip";
  EXPECT_FALSE(read_gpio_chip((sys.root / "none").string()).exists);
#if HAPTICD_WITH_HID
  const std::vector<UdcFacts> udcs = read_udcs((sys.root / "class/udc").string());
  ASSERT_EQ(udcs.size(), 1u);
  EXPECT_EQ(udcs[0].name, "pinctrl-bcm2835.0");
  EXPECT_EQ(udcs[0].driver, "pinctrl-bcm2835");
  EXPECT_TRUE(read_udcs((sys.root / "none").string()).empty());
#endif
}

config::Config gpio_config() {
  return load_config({std::string(HAPTICD_SOURCE_DIR) + "/config/gpio.yaml", {}});
}

// `hapticd peer`'s whole check of the GPIO driver's endpoint, as the command makes it.
void check_gpio(const std::string& endpoint, const PeerEndpointPolicy& policy) {
  check_peer_endpoint(wiring::find_driver("gpio").peer, gpio_config(), endpoint, policy);
}

TEST(PeerGuard, AGpioChipOfAnotherDriverIsRefusedUnlessTheFlagSaysSo) {
  FakeSysfs sys("pinctrl-bcm2835");
  const std::string endpoint = sys.chip.string() + "," + (sys.root / "channel0").string();
  try {
    check_gpio(endpoint, {});
    FAIL() << "a board's own GPIO chip was taken";
  } catch (const config::ConfigError& e) {
    ASSERT_EQ(e.messages().size(), 1u);
    EXPECT_TRUE(has(e.messages()[0], "not gpio-sim")) << e.messages()[0];
    EXPECT_TRUE(has(e.messages()[0], "--impersonate-on-real-hardware")) << e.messages()[0];
  }
  PeerEndpointPolicy told;
  told.impersonate_on_real_hardware = true;
  EXPECT_NO_THROW(check_gpio(endpoint, told));

  FakeSysfs sim("gpio-sim");
  EXPECT_NO_THROW(check_gpio(sim.chip.string() + ",x", {}));
}

TEST(PeerGuard, ADirectoryThatIsNoGpioChipIsRefusedEvenWithTheFlag) {
  PeerEndpointPolicy told;
  told.impersonate_on_real_hardware = true;
  const std::string dir = fs::temp_directory_path().string();
  EXPECT_THROW(check_gpio(dir + "," + dir + "/x", told), hapticd::DeviceError);
}
#endif

#if HAPTICD_WITH_CAN
using sim::describe_node_frame;
using sim::node_probe;
using sim::sent_by_node;

drivers::can::CanFrame frame(std::uint32_t id, std::uint8_t len, bool rtr = false) {
  drivers::can::CanFrame f = drivers::can::make_frame(id, len);
  f.rtr = rtr;
  return f;
}

TEST(PeerGuard, ACanopenNodeIsHeardByWhatItSendsNotByWhatAMasterSendsIt) {
  drivers::can::CanSettings s;
  s.nodes.front().node_id = 1;
  for (std::uint32_t id : {0x701u, 0x181u, 0x281u, 0x381u, 0x481u, 0x581u, 0x081u}) {
    EXPECT_TRUE(sent_by_node(frame(id, 1), s)) << std::hex << id;
  }
  for (std::uint32_t id : {0x080u, 0x000u, 0x201u, 0x601u, 0x77Fu, 0x702u, 0x182u}) {
    EXPECT_FALSE(sent_by_node(frame(id, 1), s))
        << "a master's, or another node's: " << std::hex << id;
  }
  EXPECT_FALSE(sent_by_node(frame(0x701, 0, true), s)) << "node guarding asks with a remote frame";
  drivers::can::CanFrame hb = frame(0x701, 1);
  hb.data[0] = 0x7F;
  EXPECT_EQ(describe_node_frame(hb, s), "0x701, the heartbeat of node 1 (pre-operational)");
  EXPECT_EQ(describe_node_frame(frame(0x581, 8), s), "0x581, an SDO reply of node 1");
  const drivers::can::CanFrame probe = node_probe(s);
  EXPECT_EQ(probe.id, 0x601u);
  EXPECT_EQ(probe.data[0], 0x40) << "an SDO upload request";
  EXPECT_EQ(probe.data[1] | probe.data[2] << 8, 0x1000) << "of the device type";
}

TEST(PeerGuard, AnOdriveIsHeardByItsHeartbeatAndItsAnswers) {
  drivers::can::CanSettings s;
  s.profile = drivers::can::Profile::kOdrive;
  s.nodes.front().node_id = 3;
  EXPECT_TRUE(sent_by_node(frame(3 << 5 | 0x01, 8), s)) << "heartbeat";
  EXPECT_TRUE(sent_by_node(frame(3 << 5 | 0x09, 8), s)) << "encoder estimates";
  EXPECT_FALSE(sent_by_node(frame(3 << 5 | 0x09, 8, true), s)) << "a master's request for them";
  EXPECT_FALSE(sent_by_node(frame(3 << 5 | 0x0E, 4), s)) << "a master's torque command";
  EXPECT_FALSE(sent_by_node(frame(3 << 5 | 0x07, 4), s)) << "a master's Set_Axis_State";
  EXPECT_FALSE(sent_by_node(frame(4 << 5 | 0x01, 8), s)) << "node 4's heartbeat";
  EXPECT_EQ(describe_node_frame(frame(3 << 5 | 0x01, 8), s),
            "0x061, the heartbeat of ODrive node 3");
  const drivers::can::CanFrame probe = node_probe(s);
  EXPECT_EQ(probe.id, 3u << 5 | 0x09);
  EXPECT_TRUE(probe.rtr);
}
#endif

}  // namespace
}  // namespace hapticd::service
