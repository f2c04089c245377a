#include "drivers/gpio/gpio_device.h"

#include <algorithm>
#include <cmath>

#include "base/errno_text.h"

namespace hapticd::drivers::gpio {
namespace {

constexpr std::uint32_t kDetailMask = 0x003F'FFFFu;
constexpr unsigned kJointShift = 22;
static_assert(wire::kMaxJoints == base::kMaxJoints && base::kMaxJoints <= 4,
              "the wire and the fault code carry a joint in two bits");

DecoderConfig decoder_config(const GpioSettings& s, std::size_t joint) {
  const GpioJointSettings& j = s.joints[joint];
  DecoderConfig c;
  c.start_count = j.start_count;
  c.has_index = j.line_index.has_value();
  c.index_count = j.index_count;
  c.max_edge_rate_hz = s.max_edge_rate_hz;
  return c;
}

std::string schema_number(double v) {
  std::string s = std::to_string(v);
  s.erase(s.find_last_not_of('0') + 1);
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

std::string errno_text(std::uint32_t detail) {
  return base::errno_text(static_cast<int>(detail)) + " (errno " + std::to_string(detail) + ")";
}

}  // namespace

std::uint32_t fault_code(FaultKind kind, std::uint64_t detail, std::size_t joint) noexcept {
  return (static_cast<std::uint32_t>(kind) << 24) |
         (static_cast<std::uint32_t>(joint & 3u) << kJointShift) |
         static_cast<std::uint32_t>(std::min<std::uint64_t>(detail, kDetailMask));
}

GpioDevice::Joint::Joint(const GpioSettings& s, std::size_t i)
    : decoder(decoder_config(s, i)),
      direction_level(s.joints[i].direction_positive_high),
      missed_times(s.missed_edge_fault + 1, 0) {}

void GpioDevice::Joint::restart(std::uint8_t levels) noexcept {
  decoder.reset(levels);
  std::fill(missed_times.begin(), missed_times.end(), 0);
  missed_next = 0;
  missed_seen = 0;
}

GpioDevice::GpioDevice(const GpioSettings& settings, std::span<const double> max_force,
                       std::unique_ptr<GpioTransport> transport, int declared_delay)
    : s_(settings), transport_(std::move(transport)), declared_delay_(declared_delay) {
  joints_.reserve(s_.joints.size());
  for (std::size_t i = 0; i < s_.joints.size(); ++i) {
    joints_.emplace_back(s_, i);
    joints_.back().max_force = max_force[i];
  }
}

// RT-safe. Records the missed edges joint j's decoder counted since the last read, at `now_ns`.
void GpioDevice::note_missed(Joint& j, std::int64_t now_ns) noexcept {
  const std::uint64_t total = j.decoder.missed_edges();
  const std::uint64_t fresh = std::min<std::uint64_t>(total - j.missed_seen, j.missed_times.size());
  j.missed_seen = total;
  for (std::uint64_t i = 0; i < fresh; ++i) {
    j.missed_times[j.missed_next] = now_ns;
    j.missed_next = (j.missed_next + 1) % j.missed_times.size();
  }
}

std::uint8_t GpioDevice::logical_levels(std::uint8_t raw) const noexcept {
  const std::uint8_t enc = wire::kLevelA | wire::kLevelB | wire::kLevelIndex;
  std::uint8_t l = s_.encoder_active_low ? static_cast<std::uint8_t>(raw ^ enc) : raw;
  if (s_.fault_active_low) l ^= wire::kLevelFault;
  return l;
}

bool GpioDevice::logical(const Edge& e) const noexcept {
  return e.line == Line::kFault ? e.level != s_.fault_active_low : e.level != s_.encoder_active_low;
}

// The channel is enabled from configure on, whatever the device's state: a stop is duty 0 on
// the enabled channel (sysfs_pwm.h says why).
OutputState GpioDevice::output(std::size_t joint, std::uint64_t duty_ns) const noexcept {
  OutputState o;
  o.joint = static_cast<std::uint8_t>(joint);
  o.duty_ns = duty_ns;
  o.period_ns = s_.pwm_period_ns;
  o.pwm_enabled = true;
  o.direction_level = joints_[joint].direction_level;
  o.inversed = s_.pwm_inversed;
  return o;
}

// "joint 1 (...): " before what a message says of that joint; nothing for a device of one joint,
// whose messages stay as they were.
std::string GpioDevice::who(std::size_t joint) const {
  return s_.listed ? s_.joint_name(joint) + ": " : "";
}

DeviceInfo GpioDevice::on_configure() {
  std::array<OutputState, base::kMaxJoints> off{};
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    joints_[j].direction_level = s_.joints[j].direction_positive_high;
    off[j] = output(j, 0);
  }
  const JointLevels raw = transport_->open(std::span(off.data(), joints_.size()));
  previous_complete_ns_ = 0;
  counters_[0].set(0);
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const std::uint8_t levels = logical_levels(raw[j]);
    joints_[j].restart(levels);
    joints_[j].fault_line = s_.joints[j].line_fault && (levels & wire::kLevelFault) != 0;
    if (joints_[j].fault_line) {
      throw DeviceError("gpio: " + who(j) + "the motor driver reports a fault (line " +
                        std::to_string(*s_.joints[j].line_fault) +
                        " active) before anything was enabled");
    }
  }
  DeviceInfo info;
  info.description = transport_->describe();
  info.transport_delay_samples = declared_delay_;
  info.sequence_modulus = 0;  // GPIO samples carry no sequence of their own
  info.joints = joints_.size();
  return info;
}

// The channels run at duty 0 since configure: output is on from the first non-zero duty.
void GpioDevice::on_enable() {}

// Duty 0 on every enabled channel: the one stop whose output Linux defines.
void GpioDevice::on_disable() noexcept {
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    transport_->write_output(output(j, 0));  // best effort: the transport may be what failed
  }
}

void GpioDevice::on_clear_fault() {
  const JointLevels raw = transport_->read_levels();
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    if (s_.joints[j].line_fault && (logical_levels(raw[j]) & wire::kLevelFault) != 0) {
      throw DeviceError("gpio: " + who(j) + "the motor driver still reports a fault (line " +
                        std::to_string(*s_.joints[j].line_fault) + " active)");
    }
  }
  // The counts are kept (they may be off by the edges that were missed: re-home on the
  // index); the counters start over so the tolerance applies afresh.
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    Joint& joint = joints_[j];
    joint.fault_line = false;
    DecoderConfig keep = decoder_config(s_, j);
    keep.start_count = joint.decoder.count();
    joint.decoder = QuadratureDecoder(keep);
    joint.restart(logical_levels(raw[j]));
  }
}

void GpioDevice::on_close() noexcept { transport_->close(); }

IoStatus GpioDevice::check_faults(std::size_t joint) noexcept {
  Joint& j = joints_[joint];
  if (j.fault_line) {
    set_fault_code(fault_code(FaultKind::kFaultLine, 0, joint));
    return IoStatus::kDeviceFault;
  }
  if (j.decoder.rate_exceeded()) {
    set_fault_code(fault_code(
        FaultKind::kEdgeRate,
        static_cast<std::uint64_t>(std::min(j.decoder.exceeded_rate_hz(), double{kDetailMask})),
        joint));
    return IoStatus::kDeviceFault;
  }
  // The oldest of the last missed_edge_fault + 1 missed edges, within the window: too many.
  const std::size_t n = j.missed_times.size();
  const std::int64_t oldest = j.missed_times[j.missed_next];
  const std::int64_t newest = j.missed_times[(j.missed_next + n - 1) % n];
  if (j.missed_seen > s_.missed_edge_fault &&
      newest - oldest <= std::llround(s_.missed_edge_window_s * 1e9)) {
    set_fault_code(fault_code(FaultKind::kMissedEdges, j.missed_seen, joint));
    return IoStatus::kDeviceFault;
  }
  return IoStatus::kOk;
}

// RT-safe. Joint j's sample after the read `r`.
void GpioDevice::sample(std::size_t joint, const EdgeRead& r, std::uint64_t ab_before,
                        std::uint64_t hits_before, PositionSample& out) const noexcept {
  const QuadratureDecoder& d = joints_[joint].decoder;
  const bool moved = d.edges() != ab_before;
  out.position = static_cast<double>(d.count()) / s_.joints[joint].counts_per_unit;
  // The last edge's time when it came since the previous read; edges older than that (the
  // backlog of the first read after configure) changed the position long ago, and the
  // position is current as of the read: its time then.
  const bool edge_time =
      moved && previous_complete_ns_ != 0 && d.last_edge_ns() >= previous_complete_ns_;
  const std::int64_t read_time =
      r.complete_until_ns != 0 ? r.complete_until_ns : previous_complete_ns_;
  out.time_ns = edge_time ? d.last_edge_ns() : read_time;
  out.flags = kSampleHasTime;
  out.status = (moved ? 0u : kStatusNoEdge) | (d.index_hits() != hits_before ? kStatusIndex : 0u) |
               (d.missed_edges() != 0 ? kStatusMissedEdges : 0u);
}

// RT-safe: called every tick.
IoStatus GpioDevice::on_read(std::span<PositionSample> samples) noexcept {
  std::array<std::uint64_t, base::kMaxJoints> hits_before{};
  std::array<std::uint64_t, base::kMaxJoints> ab_before{};
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    hits_before[j] = joints_[j].decoder.index_hits();
    ab_before[j] = joints_[j].decoder.edges();
  }
  const EdgeRead r = transport_->read_edges(edges_);
  for (std::size_t i = 0; i < r.count; ++i) {
    Edge e = edges_[i];
    if (e.joint >= joints_.size()) continue;  // the transports tag only configured joints
    Joint& j = joints_[e.joint];
    e.level = logical(e);
    if (e.line == Line::kFault) {
      j.fault_line = s_.joints[e.joint].line_fault && e.level;
    } else {
      j.decoder.apply(e);
    }
  }
  const std::int64_t now = r.complete_until_ns != 0 ? r.complete_until_ns : previous_complete_ns_;
  std::uint64_t missed = 0;
  bool moved = false;
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    joints_[j].decoder.add_lost(r.lost[j]);
    note_missed(joints_[j], now);
    missed += joints_[j].decoder.missed_edges();
    moved = moved || joints_[j].decoder.edges() != ab_before[j];
  }
  counters_[0].set(missed);
  if (r.error != 0) {
    set_fault_code(
        fault_code(FaultKind::kReadError, static_cast<std::uint64_t>(r.error), r.error_joint));
    return IoStatus::kTransportFault;
  }
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    if (const IoStatus f = check_faults(j); f != IoStatus::kOk) return f;
  }
  if (!moved && r.complete_until_ns == 0 && r.count == 0) return IoStatus::kNoNewData;
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    sample(j, r, ab_before[j], hits_before[j], samples[j]);
  }
  if (r.complete_until_ns != 0) previous_complete_ns_ = r.complete_until_ns;
  return IoStatus::kOk;
}

// RT-safe: called every tick. Every joint is written even after one failed: the zero the base
// class writes on a fault must reach the others.
IoStatus GpioDevice::on_write(std::span<const double> forces) noexcept {
  int error = 0;
  std::size_t failed = 0;
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    Joint& joint = joints_[j];
    const double force = forces[j];
    const double fraction = std::min(std::abs(force) / joint.max_force, 1.0);
    const auto duty =
        static_cast<std::uint64_t>(std::llround(fraction * static_cast<double>(s_.pwm_period_ns)));
    // Zero keeps the last direction: no needless toggling of the line at rest.
    if (force != 0.0) {
      joint.direction_level = (force > 0.0) == s_.joints[j].direction_positive_high;
    }
    const int e = transport_->write_output(output(j, duty));
    if (e != 0 && error == 0) {
      error = e;
      failed = j;
    }
  }
  if (error != 0) {
    set_fault_code(fault_code(FaultKind::kWriteError, static_cast<std::uint64_t>(error), failed));
    return IoStatus::kTransportFault;
  }
  return IoStatus::kOk;
}

std::string GpioDevice::describe(const DeviceFault& fault) const {
  const auto kind = static_cast<FaultKind>(fault.code >> 24);
  const std::size_t joint =
      std::min<std::size_t>((fault.code >> kJointShift) & 3u, joints_.size() - 1);
  const std::uint32_t detail = fault.code & kDetailMask;
  const QuadratureDecoder& d = joints_[joint].decoder;
  const std::string gpio = "gpio: " + who(joint);
  switch (kind) {
    case FaultKind::kReadError:
      return gpio + "reading the encoder's edge events failed: " + errno_text(detail);
    case FaultKind::kWriteError:
      return gpio + "writing the PWM duty or the direction line failed: " + errno_text(detail);
    case FaultKind::kFaultLine:
      return gpio + "the motor driver's fault line (line " +
             std::to_string(s_.joints[joint].line_fault.value_or(0)) + ") went active";
    case FaultKind::kMissedEdges:
      return gpio + std::to_string(s_.missed_edge_fault + 1) + " encoder edges missed within " +
             schema_number(s_.missed_edge_window_s) +
             " s, more than device.gpio.missed_edge_fault " + std::to_string(s_.missed_edge_fault) +
             "; " + std::to_string(detail) + " since enable (" +
             std::to_string(d.repeated_levels()) + " repeated levels, " +
             std::to_string(d.illegal_transitions()) + " illegal transitions, " +
             std::to_string(d.out_of_order()) + " out of order, " + std::to_string(d.lost()) +
             " lost by the kernel): the count is no longer trusted";
    case FaultKind::kEdgeRate:
      return gpio + "encoder edges at " + std::to_string(detail) +
             " per second, faster than device.gpio.max_edge_rate " +
             std::to_string(static_cast<long long>(s_.max_edge_rate_hz)) +
             " (noise on the lines, or a motion beyond what the encoder and kernel can follow)";
  }
  return "gpio: fault code " + std::to_string(fault.code);
}

}  // namespace hapticd::drivers::gpio
