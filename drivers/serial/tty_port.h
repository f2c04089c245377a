// The serial port as the driver opens it (docs/drivers/serial.md, "The port"): raw, non-blocking,
// exclusive (TIOCEXCL and flock(2): two programs on one port each read half of every frame),
// at the configured baud rate, and quick (an FTDI port's latency timer no longer than
// latency_ms, the kernel's low-latency flag asked for). The only file of the driver that
// includes <termios.h>.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "drivers/io/unique_fd.h"
#include "drivers/serial/serial_settings.h"

namespace hapticd::drivers::serial {

struct OpenedPort {
  io::UniqueFd fd;
  std::vector<std::string> notices;  // what was found that does not stop the run
};

// Not RT-safe. Opens s.port; throws DeviceError naming the port and what went wrong (absent,
// no permission, held by another program, not a tty, an FTDI latency timer above latency_ms
// with the command that lowers it).
OpenedPort open_tty(const SerialSettings& s);

// Not RT-safe. Drops what the tty has received and not yet been read.
void discard_input(int fd) noexcept;

// Not RT-safe. The kernel's name of the tty a path leads to ("ttyUSB0" for
// /dev/serial/by-id/usb-FTDI_...), or empty when it leads nowhere.
std::string tty_name(const std::string& port);
// Not RT-safe. The kernel driver of a tty ("cdc_acm", "ftdi_sio", "pl2303"...), from sysfs;
// empty for a tty without a device (a pseudo-terminal).
std::string tty_driver(const std::string& tty, const std::string& sysfs = "/sys");
// Not RT-safe. A port whose bytes cross a wire at `baud` (any driver but cdc_acm, whose USB
// link ignores the rate): refused (DeviceError naming the keys) when one period's frames, 10
// bits a byte, do not fit in the period.
void check_wire_rate(const SerialSettings& s, const std::string& driver, double sample_period_s);

// Not RT-safe. An FTDI (ftdi_sio) port's latency timer in ms, from sysfs; nothing for any
// other kind of port. `sysfs` is /sys (a test may give another root).
std::optional<int> ftdi_latency_timer(const std::string& tty, const std::string& sysfs = "/sys");

}  // namespace hapticd::drivers::serial
