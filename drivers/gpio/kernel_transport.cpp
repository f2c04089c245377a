#include "drivers/gpio/kernel_transport.h"

#include "base/clock.h"

namespace hapticd::drivers::gpio {

KernelTransport::KernelTransport(const GpioSettings& s) : chip_(s.chip) {
  offsets_.a = s.line_a;
  offsets_.b = s.line_b;
  offsets_.index = s.line_index;
  offsets_.fault = s.line_fault;
  offsets_.direction = s.line_direction;
  channel_.sysfs_root = s.pwm_sysfs_root;
  channel_.chip = s.pwm_chip;
  channel_.channel = s.pwm_channel;
  channel_.period_ns = s.pwm_period_ns;
  channel_.inversed = s.pwm_inversed;
}

std::uint8_t KernelTransport::open(const OutputState& off) {
  lines_.open(chip_, offsets_, off.direction_level);
  direction_level_ = off.direction_level;
  try {
    pwm_.open(channel_);  // enabled at duty 0 (sysfs_pwm.h: the one defined stop)
    return lines_.read_levels();
  } catch (...) {
    close();
    throw;
  }
}

void KernelTransport::close() noexcept {
  pwm_.close();
  lines_.close();
}

std::string KernelTransport::describe() const {
  return "gpio " + lines_.describe() + ", pwm " + pwm_.path() + " (" + GpiodLines::api() + ")";
}

// RT-safe: called every tick.
EdgeRead KernelTransport::read_edges(std::span<Edge> buffer) noexcept {
  EdgeRead r;
  // Taken before the reads: every edge up to here has been timestamped by the kernel. (One
  // still in its interrupt thread may come next tick, older than this: the decoder counts
  // such an edge as out of order.)
  r.complete_until_ns = base::monotonic_ns();
  r.error = lines_.read_events(buffer, r.count, r.lost);
  return r;
}

// RT-safe: called every tick. The direction before the duty, so a new duty never drives the
// old direction. The channel stays enabled (out.pwm_enabled is always true: sysfs_pwm.h).
int KernelTransport::write_output(const OutputState& out) noexcept {
  if (out.direction_level != direction_level_) {
    if (const int e = lines_.set_direction(out.direction_level)) return e;
    direction_level_ = out.direction_level;
  }
  return pwm_.write(out.duty_ns);
}

}  // namespace hapticd::drivers::gpio
