#include "drivers/gpio/gpio_device.h"

#include <algorithm>
#include <cmath>

#include "base/errno_text.h"

namespace hapticd::drivers::gpio {
namespace {

constexpr std::uint32_t kDetailMask = 0x00FF'FFFFu;

DecoderConfig decoder_config(const GpioSettings& s) {
  DecoderConfig c;
  c.start_count = s.start_count;
  c.has_index = s.line_index.has_value();
  c.index_count = s.index_count;
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

std::uint32_t fault_code(FaultKind kind, std::uint64_t detail) noexcept {
  return (static_cast<std::uint32_t>(kind) << 24) |
         static_cast<std::uint32_t>(std::min<std::uint64_t>(detail, kDetailMask));
}

GpioDevice::GpioDevice(const GpioSettings& settings, double max_force,
                       std::unique_ptr<GpioTransport> transport, int declared_delay)
    : s_(settings),
      max_force_(max_force),
      transport_(std::move(transport)),
      declared_delay_(declared_delay),
      decoder_(decoder_config(settings)),
      direction_level_(settings.direction_positive_high),
      missed_times_(settings.missed_edge_fault + 1, 0) {}

// RT-safe. Records the missed edges the decoder counted since the last read, at `now_ns`.
void GpioDevice::note_missed(std::int64_t now_ns) noexcept {
  const std::uint64_t total = decoder_.missed_edges();
  counters_[0].set(total);
  const std::uint64_t fresh = std::min<std::uint64_t>(total - missed_seen_, missed_times_.size());
  missed_seen_ = total;
  for (std::uint64_t i = 0; i < fresh; ++i) {
    missed_times_[missed_next_] = now_ns;
    missed_next_ = (missed_next_ + 1) % missed_times_.size();
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
OutputState GpioDevice::output(std::uint64_t duty_ns) const noexcept {
  OutputState o;
  o.duty_ns = duty_ns;
  o.period_ns = s_.pwm_period_ns;
  o.pwm_enabled = true;
  o.direction_level = direction_level_;
  o.inversed = s_.pwm_inversed;
  return o;
}

DeviceInfo GpioDevice::on_configure() {
  direction_level_ = s_.direction_positive_high;
  const std::uint8_t levels = logical_levels(transport_->open(output(0)));
  decoder_.reset(levels);
  previous_complete_ns_ = 0;
  std::fill(missed_times_.begin(), missed_times_.end(), 0);
  missed_next_ = 0;
  missed_seen_ = 0;
  counters_[0].set(0);
  fault_line_ = s_.line_fault && (levels & wire::kLevelFault) != 0;
  if (fault_line_) {
    throw DeviceError("gpio: the motor driver reports a fault (line " +
                      std::to_string(*s_.line_fault) + " active) before anything was enabled");
  }
  DeviceInfo info;
  info.description = transport_->describe();
  info.transport_delay_samples = declared_delay_;
  info.sequence_modulus = 0;  // GPIO samples carry no sequence of their own
  return info;
}

// The channel runs at duty 0 since configure: output is on from the first non-zero duty.
void GpioDevice::on_enable() {}

// Duty 0 on the enabled channel: the one stop whose output Linux defines.
void GpioDevice::on_disable() noexcept {
  transport_->write_output(output(0));  // best effort: the transport may be what failed
}

void GpioDevice::on_clear_fault() {
  const std::uint8_t levels = logical_levels(transport_->read_levels());
  if (s_.line_fault && (levels & wire::kLevelFault) != 0) {
    throw DeviceError("gpio: the motor driver still reports a fault (line " +
                      std::to_string(*s_.line_fault) + " active)");
  }
  fault_line_ = false;
  // The count is kept (it may be off by the edges that were missed: re-home on the index);
  // the counters start over so the tolerance applies afresh.
  const std::int64_t count = decoder_.count();
  DecoderConfig keep = decoder_config(s_);
  keep.start_count = count;
  decoder_ = QuadratureDecoder(keep);
  decoder_.reset(levels);
  std::fill(missed_times_.begin(), missed_times_.end(), 0);
  missed_next_ = 0;
  missed_seen_ = 0;
}

void GpioDevice::on_close() noexcept { transport_->close(); }

IoStatus GpioDevice::check_faults() noexcept {
  if (fault_line_) {
    set_fault_code(fault_code(FaultKind::kFaultLine, 0));
    return IoStatus::kDeviceFault;
  }
  if (decoder_.rate_exceeded()) {
    set_fault_code(fault_code(
        FaultKind::kEdgeRate,
        static_cast<std::uint64_t>(std::min(decoder_.exceeded_rate_hz(), double{kDetailMask}))));
    return IoStatus::kDeviceFault;
  }
  // The oldest of the last missed_edge_fault + 1 missed edges, within the window: too many.
  const std::int64_t oldest = missed_times_[missed_next_];
  const std::int64_t newest =
      missed_times_[(missed_next_ + missed_times_.size() - 1) % missed_times_.size()];
  if (missed_seen_ > s_.missed_edge_fault &&
      newest - oldest <= std::llround(s_.missed_edge_window_s * 1e9)) {
    set_fault_code(fault_code(FaultKind::kMissedEdges, missed_seen_));
    return IoStatus::kDeviceFault;
  }
  return IoStatus::kOk;
}

// RT-safe: called every tick.
IoStatus GpioDevice::on_read(std::span<PositionSample> samples) noexcept {
  PositionSample& out = samples.front();  // one joint
  const EdgeRead r = transport_->read_edges(edges_);
  const std::uint64_t hits_before = decoder_.index_hits();
  const std::uint64_t ab_before = decoder_.edges();
  for (std::size_t i = 0; i < r.count; ++i) {
    Edge e = edges_[i];
    e.level = logical(e);
    if (e.line == Line::kFault) {
      fault_line_ = s_.line_fault && e.level;
    } else {
      decoder_.apply(e);
    }
  }
  decoder_.add_lost(r.lost);
  note_missed(r.complete_until_ns != 0 ? r.complete_until_ns : previous_complete_ns_);
  if (r.error != 0) {
    set_fault_code(fault_code(FaultKind::kReadError, static_cast<std::uint64_t>(r.error)));
    return IoStatus::kTransportFault;
  }
  if (const IoStatus f = check_faults(); f != IoStatus::kOk) return f;
  const bool moved = decoder_.edges() != ab_before;
  if (!moved && r.complete_until_ns == 0 && r.count == 0) return IoStatus::kNoNewData;
  out.position = static_cast<double>(decoder_.count()) / s_.counts_per_unit;
  // The last edge's time when it came since the previous read; edges older than that (the
  // backlog of the first read after configure) changed the position long ago, and the
  // position is current as of the read: its time then.
  const bool edge_time =
      moved && previous_complete_ns_ != 0 && decoder_.last_edge_ns() >= previous_complete_ns_;
  out.time_ns = edge_time ? decoder_.last_edge_ns() : r.complete_until_ns;
  if (r.complete_until_ns != 0) previous_complete_ns_ = r.complete_until_ns;
  out.flags = kSampleHasTime;
  out.status = (moved ? 0u : kStatusNoEdge) |
               (decoder_.index_hits() != hits_before ? kStatusIndex : 0u) |
               (decoder_.missed_edges() != 0 ? kStatusMissedEdges : 0u);
  return IoStatus::kOk;
}

// RT-safe: called every tick.
IoStatus GpioDevice::on_write(std::span<const double> forces) noexcept {
  const double force = forces.front();  // one joint
  const double fraction = std::min(std::abs(force) / max_force_, 1.0);
  const auto duty =
      static_cast<std::uint64_t>(std::llround(fraction * static_cast<double>(s_.pwm_period_ns)));
  // Zero keeps the last direction: no needless toggling of the line at rest.
  if (force != 0.0) direction_level_ = (force > 0.0) == s_.direction_positive_high;
  if (const int e = transport_->write_output(output(duty))) {
    set_fault_code(fault_code(FaultKind::kWriteError, static_cast<std::uint64_t>(e)));
    return IoStatus::kTransportFault;
  }
  return IoStatus::kOk;
}

std::string GpioDevice::describe(const DeviceFault& fault) const {
  const auto kind = static_cast<FaultKind>(fault.code >> 24);
  const std::uint32_t detail = fault.code & kDetailMask;
  const QuadratureDecoder& d = decoder_;
  switch (kind) {
    case FaultKind::kReadError:
      return "gpio: reading the encoder's edge events failed: " + errno_text(detail);
    case FaultKind::kWriteError:
      return "gpio: writing the PWM duty or the direction line failed: " + errno_text(detail);
    case FaultKind::kFaultLine:
      return "gpio: the motor driver's fault line (line " +
             std::to_string(s_.line_fault.value_or(0)) + ") went active";
    case FaultKind::kMissedEdges:
      return "gpio: " + std::to_string(s_.missed_edge_fault + 1) + " encoder edges missed within " +
             schema_number(s_.missed_edge_window_s) +
             " s, more than device.gpio.missed_edge_fault " + std::to_string(s_.missed_edge_fault) +
             "; " + std::to_string(detail) + " since enable (" +
             std::to_string(d.repeated_levels()) + " repeated levels, " +
             std::to_string(d.illegal_transitions()) + " illegal transitions, " +
             std::to_string(d.out_of_order()) + " out of order, " + std::to_string(d.lost()) +
             " lost by the kernel): the count is no longer trusted";
    case FaultKind::kEdgeRate:
      return "gpio: encoder edges at " + std::to_string(detail) +
             " per second, faster than device.gpio.max_edge_rate " +
             std::to_string(static_cast<long long>(s_.max_edge_rate_hz)) +
             " (noise on the lines, or a motion beyond what the encoder and kernel can follow)";
  }
  return "gpio: fault code " + std::to_string(fault.code);
}

}  // namespace hapticd::drivers::gpio
