// The serial port as the driver opens it, on a real pseudo-terminal: raw both ways, exclusive,
// refused by name when it is no tty or not there; an FTDI latency timer read from sysfs; and a
// device whose frames never come refused at configure with what did arrive.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "drivers/serial/serial_device.h"
#include "drivers/serial/tty_port.h"

namespace hapticd::drivers::serial {
namespace {

// A pseudo-terminal: the test plays the device on the master, the driver opens the slave.
struct Pty {
  io::UniqueFd master{::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK)};
  std::string slave;
  Pty() {
    char name[64];
    if (!master || ::grantpt(master.get()) != 0 || ::unlockpt(master.get()) != 0 ||
        ::ptsname_r(master.get(), name, sizeof name) != 0) {
      throw std::runtime_error("no pseudo-terminal");
    }
    slave = name;
  }
};

SerialSettings settings_for(const std::string& port) {
  SerialSettings s;
  s.port = port;
  return s;
}

// Everything `fd` has within `ms`.
std::string drain(int fd, int ms = 200) {
  std::string got;
  pollfd p{fd, POLLIN, 0};
  while (::poll(&p, 1, ms) > 0) {
    char buf[256];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) break;
    got.append(buf, static_cast<std::size_t>(n));
    ms = 20;
  }
  return got;
}

TEST(SerialTty, ThePortIsRawBothWays) {
  Pty pty;
  OpenedPort port = open_tty(settings_for(pty.slave));
  // Carriage return, XON/XOFF, ^C, a newline: a cooked tty would translate, swallow or signal.
  const std::string bytes("\r\x11\x13\x03\n\x7f\x00\xff", 8);
  ASSERT_EQ(::write(pty.master.get(), bytes.data(), bytes.size()), 8);
  EXPECT_EQ(drain(port.fd.get()), bytes) << "device to hapticd, unchanged";
  EXPECT_EQ(drain(pty.master.get(), 50), "") << "no echo";
  ASSERT_EQ(::write(port.fd.get(), bytes.data(), bytes.size()), 8);
  EXPECT_EQ(drain(pty.master.get()), bytes) << "hapticd to device, unchanged (no CR-LF)";
}

TEST(SerialTty, ASecondOpenerIsTurnedAwayByName) {
  Pty pty;
  OpenedPort first = open_tty(settings_for(pty.slave));
  try {
    open_tty(settings_for(pty.slave));
    FAIL() << "two openers of one port";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("is held by another program"), std::string::npos)
        << e.what();
  }
  first.fd.reset();
  EXPECT_NO_THROW(open_tty(settings_for(pty.slave))) << "free again once closed";
}

TEST(SerialTty, NoTtyAndNoPortAreRefusedByName) {
  try {
    open_tty(settings_for("/dev/null"));
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null: is not a terminal"), std::string::npos)
        << e.what();
  }
  try {
    open_tty(settings_for("/dev/serial/by-id/usb-nothing-here"));
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be opened"), std::string::npos) << e.what();
  }
}

TEST(SerialTty, AnFtdiPortsLatencyTimerIsReadFromSysfs) {
  const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("hapticd-sysfs-" + std::to_string(::getpid()));
  std::filesystem::create_directories(root / "class/tty/ttyUSB7/device");
  std::ofstream(root / "class/tty/ttyUSB7/device/latency_timer") << "16\n";
  EXPECT_EQ(ftdi_latency_timer("ttyUSB7", root.string()), 16);
  EXPECT_EQ(ftdi_latency_timer("ttyACM0", root.string()), std::nullopt) << "not an FTDI port";
  std::filesystem::remove_all(root);
}

TEST(SerialTty, AUartWhoseBaudCannotCarryAPeriodsFramesIsRefused) {
  SerialSettings s = settings_for("/dev/ttyUSB0");
  s.input.shape.length = 14;
  s.output.shape.length = 10;
  s.baud = 115200;  // 24 bytes, 240 bits: 2.08 ms of the wire
  try {
    check_wire_rate(s, "ftdi_sio", 1e-3);
    FAIL() << "2 ms of frames in a 1 ms period";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("device.serial.baud 115200"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(check_wire_rate(s, "cdc_acm", 1e-3)) << "a CDC-ACM link ignores the rate";
  EXPECT_NO_THROW(check_wire_rate(s, "", 1e-3)) << "a pseudo-terminal has no wire";
  s.baud = 460800;
  EXPECT_NO_THROW(check_wire_rate(s, "ftdi_sio", 1e-3));
  const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("hapticd-sysfs-drv-" + std::to_string(::getpid()));
  std::filesystem::create_directories(root / "class/tty/ttyUSB3/device");
  std::filesystem::create_directory_symlink("../../../bus/usb-serial/drivers/ftdi_sio",
                                            root / "class/tty/ttyUSB3/device/driver");
  EXPECT_EQ(tty_driver("ttyUSB3", root.string()), "ftdi_sio");
  EXPECT_EQ(tty_driver("pts7", root.string()), "");
  std::filesystem::remove_all(root);
}

// A board that answers garbage: configure gives up after answer_timeout_ms, saying what came.
TEST(SerialTty, ConfigureNamesWhatArrivedWhenNoFrameDid) {
  Pty pty;
  auto s = std::make_shared<SerialSettings>();
  s->port = pty.slave;
  s->exchange = Exchange::kStream;
  s->answer_timeout_ms = 150;
  s->input.shape = {{0xA5, 0x5A}, 4, std::nullopt};
  s->input.positions = {field::typed(field::FieldType::kI16, 2)};
  s->output.shape = {{0xA5, 0x5A}, 4, std::nullopt};
  s->output.forces = {field::typed(field::FieldType::kI16, 2)};
  SerialDevice d(
      s,
      [s] {
        OpenedPort p = open_tty(*s);
        return Port{std::move(p.fd), true, {}};
      },
      1e-3, 1);
  const std::string noise(40, '\x55');
  std::thread talk([&] {
    for (int i = 0; i < 10; ++i) {
      (void)::write(pty.master.get(), noise.data(), noise.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  try {
    d.configure();
    ADD_FAILURE() << "configured on noise";
  } catch (const DeviceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no good frame within 150 ms"), std::string::npos) << what;
    EXPECT_NE(what.find("bytes started no frame"), std::string::npos) << what;
  }
  talk.join();
  EXPECT_EQ(d.state(), DeviceState::kUnconfigured);
}

}  // namespace
}  // namespace hapticd::drivers::serial
