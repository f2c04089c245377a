#include "drivers/serial/tty_port.h"

#include <fcntl.h>
#include <linux/serial.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <fstream>

#include "base/errno_text.h"
#include "config/schema_reader.h"
#include "drivers/device.h"

namespace hapticd::drivers::serial {
namespace {

speed_t speed_of(std::uint32_t baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 500000:
      return B500000;
    case 921600:
      return B921600;
    case 1000000:
      return B1000000;
    case 1500000:
      return B1500000;
    case 2000000:
      return B2000000;
    case 3000000:
      return B3000000;
    case 4000000:
      return B4000000;
    default:
      return B0;  // the section refuses any other rate
  }
}

[[noreturn]] void fail(const std::string& port, const std::string& what, int err) {
  throw DeviceError("serial port " + port + ": " + what + ": " + base::errno_text(err));
}

// Raw bytes both ways at the rate asked, no flow control, reads that never wait (the tick
// drains what has arrived). VMIN 1 with O_NONBLOCK: an empty port reads EAGAIN and a hung-up
// one end-of-file (with VMIN 0 and VTIME 0 the line discipline returns 0 for both).
void make_raw(int fd, const SerialSettings& s, termios t) {
  ::cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB);
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  ::cfsetispeed(&t, speed_of(s.baud));
  ::cfsetospeed(&t, speed_of(s.baud));
  if (::tcsetattr(fd, TCSANOW, &t) != 0) fail(s.port, "cannot be set raw (tcsetattr)", errno);
  ::tcflush(fd, TCIOFLUSH);  // what an earlier program left in either direction
}

void check_latency(const SerialSettings& s, const std::string& tty) {
  const auto timer = ftdi_latency_timer(tty);
  if (!timer || *timer <= s.latency_ms) return;
  throw DeviceError(
      "serial port " + s.port + " (" + tty + ", an FTDI port) has a latency timer of " +
      std::to_string(*timer) + " ms, longer than device.serial.latency_ms " +
      std::to_string(static_cast<int>(std::lround(s.latency_ms))) +
      ": each frame would wait up to " + std::to_string(*timer) +
      " ms in the adapter. Lower it: echo 1 > /sys/bus/usb-serial/devices/" + tty +
      "/latency_timer (as root, until it is unplugged), or for good with the rule `hapticd "
      "udev-rules --config ...` writes");
}

}  // namespace

void discard_input(int fd) noexcept { ::tcflush(fd, TCIFLUSH); }

std::string tty_name(const std::string& port) {
  char buf[PATH_MAX];
  if (::realpath(port.c_str(), buf) == nullptr) return {};
  const std::string real(buf);
  return real.substr(real.rfind('/') + 1);
}

std::string tty_driver(const std::string& tty, const std::string& sysfs) {
  char buf[PATH_MAX];
  const std::string link = sysfs + "/class/tty/" + tty + "/device/driver";
  const ssize_t n = ::readlink(link.c_str(), buf, sizeof buf - 1);
  if (n <= 0) return {};
  const std::string target(buf, static_cast<std::size_t>(n));
  return target.substr(target.rfind('/') + 1);
}

void check_wire_rate(const SerialSettings& s, const std::string& driver, double sample_period_s) {
  if (driver.empty() || driver == "cdc_acm") return;
  const double bytes = static_cast<double>(s.input.shape.length + s.output.shape.length);
  const double wire_s = 10.0 * bytes / static_cast<double>(s.baud);
  if (wire_s <= sample_period_s) return;
  throw DeviceError("serial port " + s.port + " (" + driver + ") at device.serial.baud " +
                    std::to_string(s.baud) + ": a period's frames (" +
                    std::to_string(static_cast<int>(bytes)) + " bytes, 10 bits each) take " +
                    config::schema::format_number(std::round(wire_s * 1e5) / 100) +
                    " ms of the wire, longer than the " +
                    config::schema::format_number(sample_period_s * 1e3) +
                    " ms period: a faster baud rate, shorter frames or a lower loop.rate_hz");
}

std::optional<int> ftdi_latency_timer(const std::string& tty, const std::string& sysfs) {
  std::ifstream in(sysfs + "/class/tty/" + tty + "/device/latency_timer");
  int ms = 0;
  if (!(in >> ms)) return std::nullopt;
  return ms;
}

OpenedPort open_tty(const SerialSettings& s) {
  OpenedPort p;
  p.fd = io::UniqueFd(::open(s.port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
  if (!p.fd) fail(s.port, "cannot be opened", errno);
  termios attrs{};
  if (::tcgetattr(p.fd.get(), &attrs) != 0) fail(s.port, "is not a terminal (tcgetattr)", errno);
  if (::flock(p.fd.get(), LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) {
      throw DeviceError("serial port " + s.port +
                        " is held by another program (it holds a flock(2) lock on it: a "
                        "terminal program, ModemManager, another hapticd?); `fuser " +
                        s.port + "` names it");
    }
    fail(s.port, "cannot be locked (flock)", errno);
  }
  // Further opens fail with EBUSY (but root's): the lock alone binds only those who ask.
  if (::ioctl(p.fd.get(), TIOCEXCL) != 0)
    fail(s.port, "cannot be made exclusive (TIOCEXCL)", errno);
  make_raw(p.fd.get(), s, attrs);
  const std::string tty = tty_name(s.port);
  check_latency(s, tty);
  serial_struct ss{};
  if (::ioctl(p.fd.get(), TIOCGSERIAL, &ss) == 0) {
    ss.flags |= ASYNC_LOW_LATENCY;
    if (::ioctl(p.fd.get(), TIOCSSERIAL, &ss) != 0) {
      p.notices.push_back("serial port " + s.port + ": the low-latency flag could not be set (" +
                          base::errno_text(errno) + ")");
    }
  }
  return p;
}

}  // namespace hapticd::drivers::serial
