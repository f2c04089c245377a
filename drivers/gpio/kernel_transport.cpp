#include "drivers/gpio/kernel_transport.h"

#include <algorithm>

#include "base/clock.h"

namespace hapticd::drivers::gpio {

KernelTransport::KernelTransport(const GpioSettings& s) : joint_count_(s.joints.size()) {
  for (std::size_t i = 0; i < s.joints.size(); ++i) {
    const GpioJointSettings& j = s.joints[i];
    LineOffsets o;
    o.a = j.line_a;
    o.b = j.line_b;
    o.index = j.line_index;
    o.fault = j.line_fault;
    o.direction = j.line_direction;
    o.joint = static_cast<std::uint8_t>(i);
    // Joints on one chip share its request (the section refuses a line used twice): one read a
    // tick for all of them where the API allows it (docs/drivers/gpio.md, "Several joints").
    const std::string name = j.chip.rfind("/dev/", 0) == 0 ? j.chip.substr(5) : j.chip;
    auto chip =
        std::find_if(chips_.begin(), chips_.end(), [&](const Chip& c) { return c.name == name; });
    if (chip == chips_.end()) {
      chips_.push_back({name, {}, std::make_unique<GpiodLines>()});
      chip = chips_.end() - 1;
    }
    chip->joints.push_back(o);
    PwmChannel& c = joints_[i].channel;
    c.sysfs_root = s.pwm_sysfs_root;
    c.chip = j.pwm_chip;
    c.channel = j.pwm_channel;
    c.period_ns = s.pwm_period_ns;
    c.inversed = s.pwm_inversed;
  }
  for (Chip& c : chips_) {
    for (const LineOffsets& o : c.joints) joints_[o.joint].lines = c.lines.get();
  }
}

JointLevels KernelTransport::open(std::span<const OutputState> off) {
  try {
    for (Chip& c : chips_) {
      for (LineOffsets& o : c.joints) o.direction_level = off[o.joint].direction_level;
      c.lines->open(c.name, c.joints);
    }
    for (std::size_t j = 0; j < joint_count_; ++j) {
      joints_[j].direction_level = off[j].direction_level;
      joints_[j].pwm.open(joints_[j].channel);  // enabled at duty 0 (sysfs_pwm.h)
    }
    return read_levels();
  } catch (...) {
    close();
    throw;
  }
}

void KernelTransport::close() noexcept {
  for (std::size_t j = 0; j < joint_count_; ++j) joints_[j].pwm.close();
  for (Chip& c : chips_) c.lines->close();
}

JointLevels KernelTransport::read_levels() {
  JointLevels levels{};
  for (Chip& c : chips_) c.lines->read_levels(levels);
  return levels;
}

std::string KernelTransport::describe() const {
  std::string lines;
  for (const Chip& c : chips_) lines += (lines.empty() ? "" : "; ") + c.lines->describe();
  std::string pwm;
  for (std::size_t j = 0; j < joint_count_; ++j) {
    pwm += (j == 0 ? "" : ", ") + joints_[j].pwm.path();
  }
  return "gpio " + lines + ", pwm " + pwm + " (" + GpiodLines::api() + ")";
}

// RT-safe: called every tick. One read per chip (2.x; 1.6: one per input line).
EdgeRead KernelTransport::read_edges(std::span<Edge> buffer) noexcept {
  EdgeRead r;
  // Taken before the reads: every edge up to here has been timestamped by the kernel. (One
  // still in its interrupt thread may come next tick, older than this: the decoder counts
  // such an edge as out of order.)
  r.complete_until_ns = base::monotonic_ns();
  for (Chip& c : chips_) {
    std::size_t n = 0;
    const int e = c.lines->read_events(buffer.subspan(r.count), n, r.lost);
    r.count += n;
    if (e != 0 && r.error == 0) {
      r.error = e;
      r.error_joint = c.joints.front().joint;
    }
  }
  return r;
}

// RT-safe: called every tick for each joint. The direction before the duty, so a new duty never
// drives the old direction. The channel stays enabled (out.pwm_enabled is always true:
// sysfs_pwm.h).
int KernelTransport::write_output(const OutputState& out) noexcept {
  Joint& j = joints_[out.joint];
  if (out.direction_level != j.direction_level) {
    if (const int e = j.lines->set_direction(out.joint, out.direction_level)) return e;
    j.direction_level = out.direction_level;
  }
  return j.pwm.write(out.duty_ns);
}

// Async-signal-safe: each joint's "0" through its open duty_cycle descriptor.
void KernelTransport::emergency_stop() noexcept {
  for (std::size_t j = 0; j < joint_count_; ++j) joints_[j].pwm.emergency_stop();
}

}  // namespace hapticd::drivers::gpio
