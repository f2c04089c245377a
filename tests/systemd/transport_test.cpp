// Each transport inside hapticd@.service's sandbox, on the real kernel interface, with the
// instance's udev rules installed and applied by the machine's udevd: CAN on vcan with the
// simulated drive `hapticd peer` runs, HID through hidraw with a simulated USB device (a
// gadget on dummy_hcd), GPIO with gpio-sim and the PWM simulator. Each instance opens its
// device as user hapticd, renders the wall and stops cleanly, and the device says so.
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <thread>

#include "child_process.h"
#include "drivers/can/canopen.h"
#include "drivers/can/cia402.h"
#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/hid_settings.h"
#include "sysfs.h"
#include "transport_rig.h"
#include "usb_hid_gadget.h"
#include "vcan_interface.h"

namespace hapticd::systemd_test {
namespace {

using drivers::can::CanFrame;
namespace canopen = drivers::can::canopen;

gid_t hapticd_gid() {
  const group* g = getgrnam("hapticd");
  return g != nullptr ? g->gr_gid : static_cast<gid_t>(-1);
}

class Transport : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(install_once(), "") << "installing as a user does"; }
};

// Every frame on the bus since `listener` was made, in bus order.
std::vector<CanFrame> drain(kernel_test::CanRawSocket& listener) {
  std::vector<CanFrame> frames;
  while (const auto got = listener.receive(std::chrono::milliseconds(100))) {
    CanFrame f;
    f.id = got->frame.can_id & CAN_SFF_MASK;
    f.len = got->frame.len;
    for (int i = 0; i < 8; ++i) f.data[i] = got->frame.data[i];
    frames.push_back(f);
  }
  return frames;
}

TEST_F(Transport, CanOnVcanWithTheSimulatedDriveOfHapticdPeer) {
  kernel_test::VcanInterface bus("vcan0");
  kernel_test::CanRawSocket listener(bus, {});
  const int room = 8 << 20;  // the whole run, read after it
  ASSERT_EQ(setsockopt(listener.fd(), SOL_SOCKET, SO_RCVBUFFORCE, &room, sizeof room), 0);
  // tests/can/can_kernel_test.cpp: the rate and time-outs the emulated machine keeps, and
  // stale data tolerated for 0.5 s (the drive is a process the loaded emulator may hold up),
  // and the drive's watchdog on hapticd's heartbeat at 1 s: the emulator stalls hapticd's RT
  // thread for over 100 ms at times (CI's Debian 12 guest: wake p99.9 126 ms, then EMCY 0x8130).
  Instance can(
      "can",
      config_text(
          "can-cia402.yaml",
          guest_sets(
              {"wall.stiffness=100", "safety.stale_fault_ticks=50", "device.can.interface=vcan0",
               "device.can.sdo_timeout_ms=1000", "device.can.state_timeout_ms=2000",
               "device.can.heartbeat_timeout_ms=1000", "device.can.cia402.drive_watchdog_ms=1000",
               // The drive runs before the service starts, its hand at
               // rest until the service is up (the direction check waits
               // for rest), then pressed for as long as the test runs.
               "device.sim.operator.setpoint.start=20", "device.sim.operator.setpoint.hold=600"})));
  InstanceRules rules(can, "--subsystem-match=net --sysname-match=vcan0");
  ASSERT_EQ(rules.error(), "");
  EXPECT_FALSE(contains(rules.rules(), "ip link set")) << "no bitrate for vcan:\n" << rules.rules();
  drivers::can::testing::ChildProcess drive(
      {"/usr/bin/hapticd", "peer", "--config", can.config_path(), "--endpoint", "vcan0",
       "--duration", "120"},
      "/tmp/hapticd-systemd-can-peer.out");
  ASSERT_TRUE(drive.started());
  kernel_test::wait_until([&] { return contains(drive.output(), "peer: a simulated"); },
                          std::chrono::seconds(30), "hapticd peer on vcan0");

  ASSERT_EQ(can.systemctl("start").status, 0) << can.journal();
  EXPECT_GE(wait_for_contact(can, 50, std::chrono::seconds(60)), 50) << can.journal();
  expect_clean_stop(can, "can");
  drive.signal(SIGTERM);
  EXPECT_EQ(drive.wait(std::chrono::seconds(10)), 0) << drive.output();

  // What the drive was last told and last said: shutdown at zero torque (its power stage
  // off), then pre-operational; its own statusword: ready to switch on, not enabled.
  const std::uint8_t node = 1;
  std::optional<canopen::Rpdo1> last_command;
  std::optional<canopen::Tpdo1> last_state;
  std::optional<canopen::NmtCommand> last_nmt;
  for (const CanFrame& f : drain(listener)) {
    if (f.id == canopen::kRpdo1Base + node) {
      if (const auto c = canopen::decode_rpdo1(f)) last_command = c;
    } else if (f.id == canopen::kTpdo1Base + node) {
      if (const auto t = canopen::decode_tpdo1(f)) last_state = t;
    } else if (f.id == canopen::kNmtId) {
      if (const auto n = canopen::decode_nmt(f, node)) last_nmt = n;
    }
  }
  ASSERT_TRUE(last_command && last_state && last_nmt);
  EXPECT_EQ(last_command->controlword, 0x06) << "shutdown";
  EXPECT_EQ(last_command->target_torque, 0);
  EXPECT_EQ(last_state->statusword & 0x6F, 0x21) << "ready to switch on: the power stage off";
  EXPECT_EQ(*last_nmt, canopen::NmtCommand::kEnterPreOperational);
}

kernel_test::UsbHidGadgetConfig gadget_for(const config::Config& cfg) {
  const auto s = std::dynamic_pointer_cast<const drivers::hid::HidSettings>(cfg.device.settings);
  kernel_test::UsbHidGadgetConfig g;
  g.report_descriptor = drivers::hid::report_profile_descriptor(s->report);
  g.vendor_id = *s->select.vendor_id;
  g.product_id = *s->select.product_id;
  g.serial = "hapticd-systemd";
  g.product = "hapticd simulated HID device";
  return g;
}

TEST_F(Transport, HidThroughHidrawWithASimulatedUsbDevice) {
  // tests/hid/kernel_rig.h: dummy_hcd's timing in the emulated machine.
  const std::string yaml = config_text(
      "hid-report.yaml",
      guest_sets(
          {"wall.stiffness=250", "safety.stale_fault_ticks=50", "safety.sequence_gap_fault=20",
           "device.hid.backend=hidraw", "device.hid.select.serial=hapticd-systemd",
           // As the CAN drive's: at rest until the service is up.
           "device.sim.operator.setpoint.start=20", "device.sim.operator.setpoint.hold=600",
           // The emulated USB controller stalls output transfers when the host is loaded (a
           // clean test command's run, its sanitizer builds beside it: 10 ticks of a full OUT
           // queue at 100 Hz, wake-ups 15 ms late); 100 full ticks fault, as in the reference
           // devices' guest tests (tests/reference/hid/openffboard_kernel_test.cpp).
           "device.hid.limits.out_queue_full_fault=100"}));
  Instance hid("hid", yaml);
  const config::Config cfg = load_config(yaml, hid.config_path());
  InstanceRules rules(hid, "--subsystem-match=hidraw");  // before the device: udevd applies them
  ASSERT_EQ(rules.error(), "");
  kernel_test::UsbHidGadget gadget(gadget_for(cfg));
  SimulatedDevice device(cfg, gadget.hidg_path());
  ASSERT_EQ(sh("udevadm settle --timeout=60").status, 0);
  struct stat st {};
  ASSERT_EQ(stat(gadget.hidraw_path().c_str(), &st), 0) << gadget.hidraw_path();
  EXPECT_EQ(st.st_gid, hapticd_gid()) << gadget.hidraw_path() << ": " << rules.rules();
  EXPECT_EQ(st.st_mode & 0777, 0660u);

  ASSERT_EQ(hid.systemctl("start").status, 0) << hid.journal();
  EXPECT_GE(wait_for_contact(hid, 50, std::chrono::seconds(60)), 50) << hid.journal();
  EXPECT_TRUE(device.peer->output_on()) << "the device's amplifier while servoing";
  expect_clean_stop(hid, "hid");
  EXPECT_FALSE(device.peer->output_on()) << "the stop left the simulated amplifier on";
  EXPECT_EQ(device.peer->applied_force(), 0.0);
}

TEST_F(Transport, GpioWithGpioSimAndThePwmSimulator) {
  GpioMachine m;
  m.chip.set_pull(3, true);  // nFAULT released
  Instance gpio("gpio", m.yaml());
  InstanceRules rules(gpio, m.trigger());
  ASSERT_EQ(rules.error(), "");
  DropIn pwm_writable(gpio, m.drop_in());
  struct stat st {};
  ASSERT_EQ(stat(m.chip.dev_path().c_str(), &st), 0);
  EXPECT_EQ(st.st_gid, hapticd_gid()) << m.chip.dev_path() << ": " << rules.rules();
  ASSERT_EQ(stat((m.pwm.chip_path() + "/pwm0/duty_cycle").c_str(), &st), 0)
      << "udev exports the channel";
  EXPECT_EQ(st.st_gid, hapticd_gid());

  // The plant runs first, as a real one does: the direction check, before READY=1, pushes it.
  SimulatedDevice device(load_config(m.yaml(), gpio.config_path()), m.endpoint());
  ASSERT_EQ(gpio.systemctl("start").status, 0) << gpio.journal();
  EXPECT_GE(wait_for_contact(gpio, 50, std::chrono::seconds(60)), 50) << gpio.journal();
  EXPECT_GT(m.pwm.applied(0).duty_cycle_ns, 0u) << "the wall pushes";
  expect_clean_stop(gpio, "gpio");
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u) << "zero when the run ended";
  EXPECT_TRUE(m.pwm.applied(0).enabled) << "stopped at duty 0, the channel on";
  Shell security;
  EXPECT_LE(exposure(gpio.unit(), &security), 2.0) << "with its drop-in:\n" << security.out;
}

}  // namespace
}  // namespace hapticd::systemd_test
