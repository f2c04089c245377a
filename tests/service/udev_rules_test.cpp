// `hapticd udev-rules`: an instance's rules name exactly what its configuration names (one CAN
// interface and its bitrate, one GPIO chip and one PWM channel, one HID device by vendor and
// product id) and nothing by pattern; what a rule cannot match exactly is refused with the
// key to change.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <sstream>

#include "config/config_loader.h"
#include "process.h"
#include "service/commands/udev_rules.h"
#include "service/config_source.h"

namespace hapticd::service {
namespace {

using hapticd::testing::has;

config::Config example_config(const std::string& name, const std::vector<std::string>& sets = {}) {
  return load_config({std::string(HAPTICD_SOURCE_DIR) + "/config/" + name, sets});
}

// The rules themselves: every line that is not a comment.
std::vector<std::string> rule_lines(const std::string& text) {
  std::vector<std::string> rules;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') rules.push_back(line);
  }
  return rules;
}

[[maybe_unused]] std::string refusal(const config::Config& cfg) {
  try {
    instance_udev_rules(cfg, "arm");
  } catch (const config::ConfigError& e) {
    return e.messages().at(0);
  }
  return "";
}

TEST(UdevRules, EveryExampleGrantsOnlyGroupHapticdAndMatchesNothingByPattern) {
  int written = 0;
  for (const auto& e : std::filesystem::directory_iterator(HAPTICD_SOURCE_DIR "/config")) {
    if (e.path().extension() != ".yaml") continue;
    SCOPED_TRACE(e.path().string());
    config::Config cfg;
    try {
      cfg = example_config(e.path().filename());
    } catch (const config::ConfigError& err) {
      // A build without that driver (the sanitizer stage's) cannot load its example.
      ASSERT_TRUE(has(err.messages().at(0), "device.driver")) << err.messages()[0];
      continue;
    }
    ++written;
    const std::string text = instance_udev_rules(cfg, "arm");
    EXPECT_TRUE(has(text, "/etc/udev/rules.d/70-hapticd-arm.rules")) << text;
    for (const std::string& rule : rule_lines(text)) {
      // Every value a match key compares with is literal (ACTION's alternatives aside).
      const std::regex match(R"re((\w+(\{\w+\})?)(==|!=)"([^"]*)")re");
      for (std::sregex_iterator m(rule.begin(), rule.end(), match), end; m != end; ++m) {
        const std::string value = (*m)[4];
        if ((*m)[1] == "ACTION") continue;
        EXPECT_EQ(value.find_first_of("*?[|"), std::string::npos) << rule;
      }
      if (has(rule, "GROUP=")) {
        EXPECT_TRUE(has(rule, "GROUP=\"hapticd\", MODE=\"0660\"")) << rule;
      }
    }
  }
  EXPECT_GE(written, 2) << "config/sim.yaml and the coupling example at least";
}

#if HAPTICD_WITH_CAN
TEST(UdevRules, CanSetsTheBitrateOfTheConfiguredInterfaceAndNoOther) {
  const std::string text = instance_udev_rules(
      example_config("can-cia402.yaml", {"device.can.interface=can1", "device.can.bitrate=500000"}),
      "arm");
  const std::vector<std::string> rules = rule_lines(text);
  ASSERT_EQ(rules.size(), 1u) << text;
  EXPECT_EQ(rules[0],
            "ACTION==\"add\", SUBSYSTEM==\"net\", KERNEL==\"can1\", ATTR{type}==\"280\", "
            "RUN+=\"/sbin/ip link set can1 type can bitrate 500000 restart-ms 100\", "
            "RUN+=\"/sbin/ip link set can1 up\"");
  EXPECT_TRUE(
      rule_lines(instance_udev_rules(
                     example_config("can-odrive.yaml", {"device.can.interface=vcan0"}), "arm"))
          .empty())
      << "a virtual bus has no bitrate";
  const std::string bad = refusal(example_config("can-cia402.yaml", {"device.can.interface=can*"}));
  EXPECT_TRUE(has(bad, "device.can.interface: 'can*' cannot go into a udev rule")) << bad;
}
#endif

#if HAPTICD_WITH_GPIO
TEST(UdevRules, GpioGrantsItsChipAndExportsAndGrantsItsOneChannel) {
  const std::string text = instance_udev_rules(
      example_config("gpio.yaml", {"device.gpio.chip=/dev/gpiochip2", "device.gpio.pwm.chip=1",
                                   "device.gpio.pwm.channel=3"}),
      "arm");
  const std::vector<std::string> rules = rule_lines(text);
  ASSERT_EQ(rules.size(), 2u) << text;
  EXPECT_EQ(rules[0],
            "SUBSYSTEM==\"gpio\", KERNEL==\"gpiochip2\", GROUP=\"hapticd\", MODE=\"0660\"");
  EXPECT_EQ(rules[1],
            "ACTION==\"add|change\", SUBSYSTEM==\"pwm\", KERNEL==\"pwmchip1\", "
            "ENV{UNEXPORT}==\"\", RUN+=\"/bin/sh -c 'test -d %S%p/pwm3 || echo 3 >%S%p/export; "
            "cd %S%p/pwm3 && chgrp hapticd period duty_cycle polarity enable && chmod g+w "
            "period duty_cycle polarity enable'\"");
  for (const std::string& rule : rules) {
    EXPECT_FALSE(has(rule, "unexport")) << "the group never gets the chip's export files";
  }
  EXPECT_TRUE(has(text, "lines 0, 1, 2, 3")) << text;
}

TEST(UdevRules, AGpioChipGivenByLabelIsRefusedWithTheKeyToChange) {
  const std::string bad =
      refusal(example_config("gpio.yaml", {"device.gpio.chip=pinctrl-bcm2835"}));
  EXPECT_TRUE(has(bad,
                  "--set device.gpio.chip=pinctrl-bcm2835: device.gpio.chip: "
                  "'pinctrl-bcm2835' is not a chip's kernel name"))
      << bad;
  EXPECT_TRUE(has(bad, "gpiochipN")) << bad;
  const std::string other_root = instance_udev_rules(
      example_config("gpio.yaml", {"device.gpio.pwm.sysfs_root=/tmp/pwm"}), "arm");
  EXPECT_EQ(rule_lines(other_root).size(), 1u) << "no PWM rule for a root udev does not manage";
}
#endif

#if HAPTICD_WITH_HID
TEST(UdevRules, HidGrantsTheConfiguredDeviceByVendorProductAndSerial) {
  std::vector<std::string> rules =
      rule_lines(instance_udev_rules(example_config("hid-report.yaml"), "a"));
  ASSERT_EQ(rules.size(), 1u);
  EXPECT_EQ(rules[0],
            "SUBSYSTEM==\"hidraw\", ATTRS{idVendor}==\"1209\", ATTRS{idProduct}==\"ffb0\", "
            "GROUP=\"hapticd\", MODE=\"0660\"");
  rules = rule_lines(instance_udev_rules(
      example_config("hid-pid.yaml",
                     {"device.hid.backend=libusb", "device.hid.select.serial=0042"}),
      "a"));
  ASSERT_EQ(rules.size(), 1u);
  EXPECT_EQ(rules[0],
            "SUBSYSTEM==\"usb\", ENV{DEVTYPE}==\"usb_device\", ATTR{idVendor}==\"1209\", "
            "ATTR{idProduct}==\"ffb0\", ATTR{serial}==\"0042\", GROUP=\"hapticd\", "
            "MODE=\"0660\"");
  rules = rule_lines(instance_udev_rules(
      example_config("hid-report.yaml", {"device.hid.select.path=/dev/hidraw3"}), "a"));
  ASSERT_EQ(rules.size(), 1u);
  EXPECT_EQ(rules[0],
            "SUBSYSTEM==\"hidraw\", KERNEL==\"hidraw3\", GROUP=\"hapticd\", MODE=\"0660\"");
  const std::string bad =
      refusal(example_config("hid-report.yaml", {"device.hid.select.serial=\"00 42*\""}));
  EXPECT_TRUE(has(bad, "device.hid.select.serial: '00 42*' cannot go into a udev rule")) << bad;
}
#endif

#if HAPTICD_WITH_SERIAL
TEST(UdevRules, SerialGrantsTheConfiguredPortAndSetsAnFtdiLatencyTimer) {
  std::vector<std::string> rules = rule_lines(instance_udev_rules(
      example_config("serial-stream.yaml", {"device.serial.port=/dev/ttyUSB1"}), "arm"));
  ASSERT_EQ(rules.size(), 2u);
  EXPECT_EQ(rules[0], "SUBSYSTEM==\"tty\", KERNEL==\"ttyUSB1\", GROUP=\"hapticd\", MODE=\"0660\"");
  EXPECT_EQ(rules[1],
            "ACTION==\"add\", SUBSYSTEM==\"tty\", KERNEL==\"ttyUSB1\", DRIVERS==\"ftdi_sio\", "
            "RUN+=\"/bin/sh -c 'echo 1 >/sys%p/device/latency_timer'\"");
  // A by-id link: the properties it is made of, matched exactly.
  rules = rule_lines(instance_udev_rules(
      example_config("serial-stream.yaml", {"device.serial.port=/dev/serial/by-id/"
                                            "usb-FTDI_FT232R_USB_UART_A50285BI-if00-port0"}),
      "arm"));
  ASSERT_EQ(rules.size(), 2u);
  EXPECT_TRUE(has(rules[0],
                  "ENV{ID_BUS}==\"usb\", ENV{ID_SERIAL}==\"FTDI_FT232R_USB_UART_A50285BI\", "
                  "ENV{ID_USB_INTERFACE_NUM}==\"00\""))
      << rules[0];
  EXPECT_TRUE(has(rules[0], "ATTRS{port_number}==\"0\"")) << "that adapter port only";
  for (const char* bad :
       {"/dev/my-board", "/dev/tty0", "/dev/tty", "/dev/serial/by-id/usb-Foo-if0",
        "/dev/serial/by-id/usb-Foo-if00xyz", "/dev/serial/by-id/usb-Foo-if00/../../ttyS0"}) {
    SCOPED_TRACE(bad);
    EXPECT_TRUE(has(
        refusal(example_config("serial-stream.yaml", {std::string("device.serial.port=") + bad})),
        std::string("device.serial.port: '") + bad + "' is "));
  }
  EXPECT_TRUE(has(refusal(example_config("serial-stream.yaml", {"device.serial.latency_ms=0.5"})),
                  "device.serial.latency_ms: an FTDI adapter's latency timer is whole"));
}
#endif

#if HAPTICD_WITH_EVDEV
TEST(UdevRules, EvdevGrantsTheConfiguredInputNodeAndNoOther) {
  std::vector<std::string> rules =
      rule_lines(instance_udev_rules(example_config("evdev.yaml"), "a"));
  ASSERT_EQ(rules.size(), 1u);
  EXPECT_EQ(rules[0],
            "SUBSYSTEM==\"input\", ATTRS{id/vendor}==\"1209\", "
            "ATTRS{id/product}==\"ffb0\", GROUP=\"hapticd\", MODE=\"0660\"");
  rules = rule_lines(instance_udev_rules(
      example_config("evdev.yaml",
                     {"device.evdev.select={path: /dev/input/by-id/usb-X-event-joystick}"}),
      "a"));
  ASSERT_EQ(rules.size(), 1u);
  EXPECT_EQ(rules[0],
            "SUBSYSTEM==\"input\", SYMLINK==\"input/by-id/usb-X-event-joystick\", "
            "GROUP=\"hapticd\", MODE=\"0660\"");
  const std::string bad =
      refusal(example_config("evdev.yaml", {"device.evdev.select={name: \"Open FFBoard\"}"}));
  EXPECT_TRUE(has(bad, "device.evdev.select.name: 'Open FFBoard' cannot go into a udev rule"))
      << bad;
}
#endif

}  // namespace
}  // namespace hapticd::service
