#include <filesystem>
#include <regex>
#include <sstream>

#include "config/config_loader.h"
#include "drivers/serial/serial_driver.h"
#include "drivers/serial/serial_settings.h"
#include "drivers/serial/tty_port.h"

namespace hapticd::drivers::serial {
namespace {

namespace fs = std::filesystem;
constexpr const char* kById = "/dev/serial/by-id/";

// The udev match of the configured port: its kernel name, or the properties its by-id link is
// made of (udev's 60-serial.rules: usb-$ID_SERIAL-if$ID_USB_INTERFACE_NUM, -port$N after it for
// a USB serial adapter), each matched literally.
std::string port_match(const config::Config& cfg, const UdevRules& out, const std::string& port) {
  const auto refuse = [&](const std::string& why) {
    throw config::ConfigError(
        {cfg.locate("device.serial.port") + ": device.serial.port: '" + port + "' " + why});
  };
  static const std::regex kLink(R"(usb-([A-Za-z0-9_.:-]+)-if([0-9a-f]{2})(-port([0-9]+))?)");
  static const std::regex kKernel(R"(/dev/(tty(ACM|USB|AMA|S)[0-9]+))");
  std::smatch m;
  if (port.rfind(kById, 0) == 0) {
    const std::string link = port.substr(std::string(kById).size());
    if (!std::regex_match(link, m, kLink)) {
      refuse("is not a link udev's 60-serial.rules makes (usb-SERIAL-ifNN, -portN after it)");
    }
    std::string match = "ENV{ID_BUS}==\"usb\", ENV{ID_SERIAL}==\"" + m[1].str() +
                        "\", ENV{ID_USB_INTERFACE_NUM}==\"" + m[2].str() + "\"";
    // A USB serial adapter's port on that interface (usb-serial's port_number).
    if (m[4].matched) match += ", ATTRS{port_number}==\"" + m[4].str() + "\"";
    out.literal("device.serial.port", m[1].str());
    return match;
  }
  if (std::regex_match(port, m, kKernel)) return "KERNEL==\"" + m[1].str() + "\"";
  refuse(
      "is neither a serial port's own node (/dev/ttyACMn, ttyUSBn, ttyAMAn, ttySn) nor a "
      "/dev/serial/by-id/ link, which are what a udev rule can match exactly");
  return {};
}

}  // namespace

void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const SerialSettings& s = serial_settings(cfg);
  const std::string match = port_match(cfg, out, s.port);
  out.comment("device.serial.port: " + s.port + ", granted to the group (no other tty).");
  out.rule("SUBSYSTEM==\"tty\", " + match + out.grant());
  if (s.latency_ms < 1.0) {
    throw config::ConfigError(
        {cfg.locate("device.serial.latency_ms") +
         ": device.serial.latency_ms: an FTDI adapter's latency timer is whole milliseconds, 1 at "
         "the least: below 1 the rule cannot set what hapticd then requires"});
  }
  const int ms = static_cast<int>(s.latency_ms);
  out.comment(
      "On an FTDI adapter (ftdi_sio), its latency timer (16 ms as the kernel leaves it) "
      "set to device.serial.latency_ms, " +
      std::to_string(ms) + " ms, as it appears: hapticd refuses a port whose timer is longer.");
  out.rule("ACTION==\"add\", SUBSYSTEM==\"tty\", " + match +
           ", DRIVERS==\"ftdi_sio\", RUN+=\"/bin/sh -c 'echo " + std::to_string(ms) +
           " >/sys%p/device/latency_timer'\"");
}

std::string list_ports() {
  std::ostringstream out;
  std::error_code ec;
  int n = 0;
  for (const auto& e : fs::directory_iterator(kById, ec)) {
    const std::string tty = tty_name(e.path().string());
    const std::string driver = tty_driver(tty);
    out << "serial " << tty << " (" << (driver.empty() ? "?" : driver) << ")";
    if (const auto t = ftdi_latency_timer(tty)) out << ", latency timer " << *t << " ms";
    out << "\n  device.serial.port: " << e.path().string() << "\n";
    ++n;
  }
  if (n == 0) out << "serial: no USB serial port (" << kById << " is empty or absent)\n";
  return out.str();
}

}  // namespace hapticd::drivers::serial
