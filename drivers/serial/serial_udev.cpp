#include <filesystem>
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
  if (port.rfind(kById, 0) == 0) {
    const std::string link = port.substr(std::string(kById).size());
    const std::size_t in = link.rfind("-if");
    if (link.rfind("usb-", 0) != 0 || in == std::string::npos || in <= 4) {
      refuse("is not a link udev's 60-serial.rules makes (usb-SERIAL-ifNN)");
    }
    const std::string serial = link.substr(4, in - 4);
    const std::string iface = link.substr(in + 3, 2);
    out.literal("device.serial.port", serial);
    out.literal("device.serial.port", iface);
    return "ENV{ID_BUS}==\"usb\", ENV{ID_SERIAL}==\"" + serial +
           "\", ENV{ID_USB_INTERFACE_NUM}==\"" + iface + "\"";
  }
  if (port.rfind("/dev/tty", 0) == 0 && port.find('/', 5) == std::string::npos) {
    out.literal("device.serial.port", port.substr(5));
    return "KERNEL==\"" + port.substr(5) + "\"";
  }
  refuse(
      "is neither /dev/ttyNAME nor a /dev/serial/by-id/ link, which are what a udev rule can "
      "match exactly");
  return {};
}

std::string driver_of(const std::string& tty) {
  std::error_code ec;
  const fs::path d = fs::read_symlink("/sys/class/tty/" + tty + "/device/driver", ec);
  return ec ? std::string("?") : d.filename().string();
}

}  // namespace

void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const SerialSettings& s = serial_settings(cfg);
  const std::string match = port_match(cfg, out, s.port);
  out.comment("device.serial.port: " + s.port + ", granted to the group (no other tty).");
  out.rule("SUBSYSTEM==\"tty\", " + match + out.grant());
  const int ms = std::max(1, static_cast<int>(s.latency_ms));
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
    out << "serial " << tty << " (" << driver_of(tty) << ")";
    if (const auto t = ftdi_latency_timer(tty)) out << ", latency timer " << *t << " ms";
    out << "\n  device.serial.port: " << e.path().string() << "\n";
    ++n;
  }
  if (n == 0) out << "serial: no USB serial port (" << kById << " is empty or absent)\n";
  return out.str();
}

}  // namespace hapticd::drivers::serial
