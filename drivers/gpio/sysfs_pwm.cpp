#include "drivers/gpio/sysfs_pwm.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>

#include "base/errno_text.h"
#include "drivers/device.h"

namespace hapticd::drivers::gpio {
namespace {

std::string err_text(int e) {
  if (e == EACCES || e == EPERM) {
    return base::errno_text(e) +
           " (`hapticd udev-rules` writes the rules that give group hapticd access)";
  }
  return base::errno_text(e);
}

// Not RT-safe: set-up writes of whole text values.
void write_text(const std::string& path, const std::string& text) {
  io::UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CLOEXEC));
  if (!fd) throw DeviceError("gpio: cannot open " + path + ": " + err_text(errno));
  const std::string line = text + "\n";
  if (::write(fd.get(), line.data(), line.size()) != static_cast<ssize_t>(line.size())) {
    throw DeviceError("gpio: cannot write '" + text + "' to " + path + ": " + err_text(errno));
  }
}

bool writable(const std::string& path) { return ::access(path.c_str(), W_OK) == 0; }

void sleep_ms(int ms) {
  timespec ts{0, static_cast<long>(ms) * 1'000'000};
  nanosleep(&ts, nullptr);
}

std::string read_first_word(const std::string& path) {
  io::UniqueFd fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (!fd) return {};
  char buf[64] = {};
  const ssize_t n = ::read(fd.get(), buf, sizeof buf - 1);
  if (n <= 0) return {};
  std::string s(buf, static_cast<std::size_t>(n));
  return s.substr(0, s.find_first_of(" \n"));
}

}  // namespace

void SysfsPwm::open(const PwmChannel& ch) {
  close();
  const std::string chip_dir = ch.sysfs_root + "/pwmchip" + std::to_string(ch.chip);
  struct stat st {};
  if (::stat(chip_dir.c_str(), &st) != 0) {
    throw DeviceError("gpio: no PWM chip at " + chip_dir + ": " + err_text(errno) +
                      " (device.gpio.pwm.chip, pwm.sysfs_root)");
  }
  const std::string dir = chip_dir + "/pwm" + std::to_string(ch.channel);
  // Exported already (by the instance's udev rule, as root: the chip's export file may stay
  // root's, so the group cannot take or release another channel; or by an earlier run).
  if (::stat(dir.c_str(), &st) != 0) {
    io::UniqueFd exp(::open((chip_dir + "/export").c_str(), O_WRONLY | O_CLOEXEC));
    if (!exp) throw DeviceError("gpio: cannot open " + chip_dir + "/export: " + err_text(errno));
    const std::string n = std::to_string(ch.channel) + "\n";
    // EBUSY: exported already (by an earlier run: a channel stays exported) or held by a
    // kernel driver; the files tell which.
    if (::write(exp.get(), n.data(), n.size()) < 0 && errno != EBUSY) {
      throw DeviceError("gpio: cannot export channel " + std::to_string(ch.channel) + " of " +
                        chip_dir + ": " + err_text(errno));
    }
  }
  int waited = 0;  // udev gives the new files their group a moment after they appear
  for (; !writable(dir + "/duty_cycle") && waited < kExportWaitMs; waited += 10) sleep_ms(10);
  if (!writable(dir + "/duty_cycle")) {
    throw DeviceError("gpio: " + dir + "/duty_cycle is not there or not writable " +
                      std::to_string(kExportWaitMs) + " ms after the export: " + err_text(errno) +
                      " (a kernel driver may hold the channel)");
  }
  // Order matters. A duty left non-zero goes to 0 before anything else: a channel some earlier
  // run or tool left driving stops at once, at its defined level while enabled (a fresh
  // channel's duty is 0 already, and some kernels' core refuses any write while its period is
  // 0). Then the period (the core refuses one below the duty), and the polarity, which the
  // core changes only on a disabled channel.
  const std::string duty = read_first_word(dir + "/duty_cycle");
  std::uint64_t current = 0;
  std::from_chars(duty.data(), duty.data() + duty.size(), current);  // unreadable: 0
  if (current != 0) write_text(dir + "/duty_cycle", "0");
  write_text(dir + "/period", std::to_string(ch.period_ns));
  write_text(dir + "/duty_cycle", "0");
  bool enabled = read_first_word(dir + "/enable") == "1";
  const char* polarity = ch.inversed ? "inversed" : "normal";
  if (read_first_word(dir + "/polarity") != polarity) {
    if (enabled) write_text(dir + "/enable", "0");
    enabled = false;
    write_text(dir + "/polarity", polarity);
  }
  if (!enabled) write_text(dir + "/enable", "1");

  duty_fd_.reset(::open((dir + "/duty_cycle").c_str(), O_WRONLY | O_CLOEXEC));
  if (!duty_fd_) {
    const int e = errno;
    throw DeviceError("gpio: cannot open " + dir + "/duty_cycle: " + err_text(e));
  }
  dir_ = dir;
  duty_ns_ = 0;
}

void SysfsPwm::close() noexcept { duty_fd_.reset(); }

// RT-safe. One write(2) of the decimal value and a newline; sysfs ignores the file offset.
int SysfsPwm::write_value(int fd, std::uint64_t value) noexcept {
  char buf[24];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf - 1, value);
  *end++ = '\n';
  const auto len = static_cast<std::size_t>(end - buf);
  ++writes_;
  const ssize_t n = ::write(fd, buf, len);
  if (n == static_cast<ssize_t>(len)) return 0;
  return n < 0 ? errno : EIO;
}

// RT-safe: called every tick.
int SysfsPwm::write(std::uint64_t duty_ns) noexcept {
  if (!duty_fd_) return EBADF;
  if (duty_ns == duty_ns_) return 0;
  if (const int e = write_value(duty_fd_.get(), duty_ns)) return e;
  duty_ns_ = duty_ns;
  return 0;
}

// Async-signal-safe: write(2) of a constant on an open descriptor.
void SysfsPwm::emergency_stop() noexcept {
  const int fd = duty_fd_.get();
  if (fd < 0) return;
  [[maybe_unused]] const ssize_t n = ::write(fd, "0\n", 2);
}

}  // namespace hapticd::drivers::gpio
