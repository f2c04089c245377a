// A sysfs PWM channel (<root>/pwmchipN/pwmM: export, period, duty_cycle, polarity, enable),
// the GPIO driver's force output. The root is configurable (/sys/class/pwm on a real board; a
// test's own directory). The duty is written only when it changes, through a descriptor opened
// once, so a tick costs one write(2) at most. emergency_stop() writes "0" to the open
// duty_cycle descriptor and is async-signal-safe.
//
// The channel is enabled at open() and never disabled again: Linux defines the output of an
// enabled channel at duty 0 (the inactive level) and leaves a disabled channel's output
// undefined (Documentation/driver-api/pwm.rst: it may keep driving), so every stop is duty 0
// on the enabled channel.
//
// What it cannot do: a sysfs PWM keeps its last duty when the process dies. Failing safe when
// hapticd is killed needs hardware that notices (docs/drivers/gpio.md).
#pragma once

#include <cstdint>
#include <string>

#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::gpio {

struct PwmChannel {
  std::string sysfs_root = "/sys/class/pwm";
  unsigned chip = 0;
  unsigned channel = 0;
  std::uint64_t period_ns = 50'000;
  bool inversed = false;
};

class SysfsPwm {
 public:
  // How long open() waits for the channel's files to appear (and udev to give them their
  // group) after an export.
  static constexpr int kExportWaitMs = 2000;

  // Not RT-safe. Exports the channel unless it is exported already (an EBUSY from the export
  // is fine too: the files are there; EBUSY with no files means a kernel driver holds it), then
  // writes duty 0 first (a channel left running by someone else stops at its defined level),
  // the period, the polarity (the core changes it only on a disabled channel: the one moment
  // the channel is off, at duty 0), and enable 1, ending enabled at duty 0. Throws DeviceError
  // naming the file and the reason.
  void open(const PwmChannel& channel);
  // Not RT-safe. Closes the descriptor; the channel stays exported and enabled at the last
  // duty written (0 after every stop).
  void close() noexcept;
  bool is_open() const noexcept { return static_cast<bool>(duty_fd_); }

  // RT-safe: called every tick. Writes the duty if it differs from the last write; 0 or the
  // errno.
  int write(std::uint64_t duty_ns) noexcept;
  // Async-signal-safe.
  void emergency_stop() noexcept;

  const std::string& path() const noexcept { return dir_; }
  std::uint64_t writes() const noexcept { return writes_; }  // write(2) calls made by write()

 private:
  int write_value(int fd, std::uint64_t value) noexcept;

  std::string dir_;
  io::UniqueFd duty_fd_;
  std::uint64_t duty_ns_ = 0;
  std::uint64_t writes_ = 0;
};

}  // namespace hapticd::drivers::gpio
