#include "drivers/hid/hid_device.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <thread>

#include "base/clock.h"
#include "base/errno_text.h"

namespace hapticd::drivers::hid {

HidDevice::HidDevice(std::shared_ptr<const HidSettings> settings,
                     std::function<std::unique_ptr<HidTransport>()> open, double sample_period_s)
    : settings_(std::move(settings)),
      open_(std::move(open)),
      period_s_(sample_period_s),
      liveness_ns_(static_cast<std::int64_t>(settings_->liveness_ms * 1e6)) {}

HidDevice::~HidDevice() { close(); }

DeviceInfo HidDevice::on_configure() {
  for (base::Counter& c : c_) c.set(0);
  logged_ = {};
  decoded_ = {};
  active_ = false;
  transport_ = open_();
  profile_ = settings_->profile == Profile::kReport ? make_report_profile(*settings_)
                                                    : make_pid_profile(*settings_, period_s_);
  profile_->configure(*transport_);
  transport_->set_safe_reports(profile_->safe_reports());
  emergency_.store(transport_.get());
  return {transport_->describe() + ", " + profile_->summary(),
          declared_delay_samples(*settings_, period_s_), profile_->sequence_modulus(),
          profile_->joints()};
}

// Whatever the device said before output was enabled (a status from before, samples of the
// plant at rest) is not this run's: drop it, so the first tick judges only what follows.
void HidDevice::drain_stale() noexcept {
  for (int i = 0; i < kMaxDrain; ++i) {
    if (transport_->read(rx_).status != TransportIo::kOk) break;
  }
  decoded_.status = 0;
  have_position_ = false;
}

// A device that reports on change may say nothing for its whole resend interval: the enable
// waits (up to the liveness bound) for one report, so the first tick has a position it can
// trust, never one from before the reports buffered while nobody read them.
void HidDevice::await_first_sample() {
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::nanoseconds(static_cast<std::int64_t>(liveness_ns_));
  while (std::chrono::steady_clock::now() < end) {
    const Drained d = drain();
    if (d.error != 0) {
      throw DeviceError(std::string("hid: reading the device at enable: ") +
                        base::errno_text(d.error));
    }
    if (d.samples > 0) {
      have_position_ = true;
      last_report_ns_ = base::monotonic_ns();
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  throw DeviceError("hid: the device sent no input report within device.hid.liveness_ms (" +
                    std::to_string(settings_->liveness_ms) +
                    " ms) of the enable: is it hung, or is liveness_ms shorter than the "
                    "interval at which it repeats an unchanged report?");
}

void HidDevice::on_enable() {
  drain_stale();
  queue_full_streak_ = 0;
  pending_count_ = 0;
  profile_->enable(*transport_);
  transport_->set_safe_reports(profile_->safe_reports());  // now naming the effect it made
  if (settings_->reports_on_change) await_first_sample();
  active_ = true;
}

void HidDevice::on_disable() noexcept {
  active_ = false;
  if (!transport_) return;
  transport_->write_safe();
  profile_->disable(*transport_);
  transport_->flush(std::chrono::milliseconds(static_cast<long>(settings_->limits.timeout_ms)));
  log_counters();
}

void HidDevice::on_close() noexcept {
  active_ = false;
  emergency_.store(nullptr);
  if (transport_) log_counters();
  profile_.reset();
  transport_.reset();
}

void HidDevice::emergency_stop() noexcept {
  if (HidTransport* t = emergency_.load()) t->emergency();
}

// One report carries every joint's position: each joint's sample shares its time, sequence and
// status, and a held tick holds them all.
IoStatus HidDevice::on_read(std::span<PositionSample> samples) noexcept {
  const IoStatus s = read_joint0(samples.front());
  if (s != IoStatus::kOk) return s;
  for (std::size_t j = 1; j < samples.size(); ++j) {
    samples[j] = samples.front();
    samples[j].position = decoded_.position[j];
  }
  return s;
}

IoStatus HidDevice::read_joint0(PositionSample& out) noexcept {
  const Drained d = drain();
  if (d.error != 0) {
    set_fault_code(static_cast<std::uint32_t>(d.error));
    return IoStatus::kTransportFault;
  }
  out.status = decoded_.status;
  if (active_ && profile_->fault_bits(decoded_.status) != 0) {
    set_fault_code(decoded_.status);
    return IoStatus::kDeviceFault;
  }
  const std::int64_t now = base::monotonic_ns();
  if (d.reports > 0) last_report_ns_ = now;
  if (d.samples == 0) return hold(out, now);
  have_position_ = true;
  out.position = decoded_.position[0];
  out.time_ns = now;  // hidapi gives no kernel time stamp: when it was read
  out.flags = kSampleHasTime;
  out.samples = d.samples;
  // A device that reports on change numbers the samples it did not send too: its gaps are
  // unchanged positions, not lost ones (docs/drivers/hid.md), so they are not counted.
  if (decoded_.has_sequence && !settings_->reports_on_change) {
    out.sequence = decoded_.sequence;
    out.flags |= kSampleHasSequence;
  }
  if (decoded_.has_velocity) {
    out.velocity = decoded_.velocity;
    out.flags |= kSampleHasVelocity;
  }
  return IoStatus::kOk;
}

// A tick without a sample. From a device that reports every period it is stale data (the loop
// counts it). From one that reports on change it means nothing moved: the last position is
// the current one, for as long as the device shows it is alive within the liveness bound.
IoStatus HidDevice::hold(PositionSample& out, std::int64_t now) noexcept {
  if (!settings_->reports_on_change || !have_position_) return IoStatus::kNoNewData;
  if (now - last_report_ns_ > liveness_ns_) {
    set_fault_code(ETIMEDOUT);
    return IoStatus::kTransportFault;
  }
  bump(kHeld);
  out.position = decoded_.position[0];
  out.time_ns = now;  // nothing changed up to now: the position is current as of now
  out.flags = kSampleHasTime | kSampleHeld;
  if (decoded_.has_velocity) {
    out.velocity = 0.0;  // the device would have reported a moving axis
    out.flags |= kSampleHasVelocity;
  }
  return IoStatus::kOk;
}

HidDevice::Drained HidDevice::drain() noexcept {
  Drained d;
  int i = 0;
  for (; i < kMaxDrain; ++i) {
    const IoResult r = transport_->read(rx_);
    if (r.status == TransportIo::kEmpty) break;
    if (r.status == TransportIo::kError) {
      if (r.error == EMSGSIZE) {
        bump(kTooLong);
        continue;
      }
      d.error = r.error;
      return d;
    }
    switch (profile_->decode({rx_.data(), r.size}, decoded_)) {
      case InputKind::kPosition:
        if (d.samples > 0) bump(kSuperseded);
        ++d.samples;
        ++d.reports;
        bump(kInputReports);
        break;
      case InputKind::kState:
        ++d.reports;
        bump(kStateReports);
        break;
      case InputKind::kOther:
        bump(kUnknownId);
        break;
      case InputKind::kTooShort:
        bump(kTooShort);
        break;
      case InputKind::kTooLong:
        bump(kTooLong);
        break;
    }
  }
  if (i == kMaxDrain) bump(kDrainLimit);
  return d;
}

IoStatus HidDevice::send(std::span<const std::uint8_t> report, bool& written) noexcept {
  const IoResult r = transport_->write(report);
  written = r.status == TransportIo::kOk;
  if (written) {
    queue_full_streak_ = 0;
    bump(kOutputReports);
    return IoStatus::kOk;
  }
  if (r.status == TransportIo::kError) {
    set_fault_code(static_cast<std::uint32_t>(r.error));
    return IoStatus::kTransportFault;
  }
  bump(kOutQueueFull);
  if (++queue_full_streak_ >= settings_->limits.out_queue_full_fault) {
    set_fault_code(ENOBUFS);
    return IoStatus::kTransportFault;
  }
  return IoStatus::kOk;  // this tick's command is lost; the next one follows
}

// RT-safe: called every tick. Keeps `r` to send ahead of the force; a report already kept (the
// same effect's restart, due again before the queue took it) is not kept twice.
void HidDevice::queue_pending(std::span<const std::uint8_t> r) noexcept {
  if (r.empty()) return;
  for (std::size_t i = 0; i < pending_count_; ++i) {
    if (pending_[i].data() == r.data()) return;
  }
  if (pending_count_ < pending_.size()) pending_[pending_count_++] = r;
}

IoStatus HidDevice::on_write(std::span<const double> forces) noexcept {
  if (state() == DeviceState::kFaulted) {  // after a fault nothing but zero, ahead of the queue
    transport_->write_safe();
    return IoStatus::kOk;
  }
  // A report due before the force (an effect's restart) that the full queue could not take is
  // sent at the next tick that can: dropped, the effect would run out on the device and the
  // wall with it, however long the queue stays full. A tick whose queue took not even that
  // one has no room for its force either: it is one dropped tick, counted once.
  queue_pending(profile_->before_force());
  bool written = true;
  while (pending_count_ > 0) {
    const IoStatus s = send(pending_[0], written);
    if (s != IoStatus::kOk || !written) return s;
    std::copy(pending_.begin() + 1, pending_.begin() + static_cast<std::ptrdiff_t>(pending_count_),
              pending_.begin());
    --pending_count_;
  }
  // A report the full queue did not take ends the tick: the reports after it would render
  // some joints' forces of this tick beside others' of the last.
  for (const std::span<const std::uint8_t> r : profile_->force_reports(forces)) {
    const IoStatus s = send(r, written);
    if (s != IoStatus::kOk || !written) return s;
  }
  return IoStatus::kOk;
}

HidCounters HidDevice::hid_counts() const noexcept {
  return {c_[kInputReports].value(),  c_[kSuperseded].value(),   c_[kStateReports].value(),
          c_[kUnknownId].value(),     c_[kTooShort].value(),     c_[kTooLong].value(),
          c_[kOutputReports].value(), c_[kOutQueueFull].value(), c_[kDrainLimit].value(),
          c_[kHeld].value()};
}

void HidDevice::log_counters() const {
  const HidCounters k = hid_counts();
  const std::uint64_t malformed = k.unknown_id + k.too_short + k.too_long;
  if (malformed > logged_.unknown_id + logged_.too_short + logged_.too_long) {
    spdlog::warn(
        "hid: {} input reports were malformed: {} of an unknown id, {} too short, {} too "
        "long (of {} samples)",
        malformed, k.unknown_id, k.too_short, k.too_long, k.input_reports);
  }
  if (k.out_queue_full > logged_.out_queue_full) {
    spdlog::warn(
        "hid: {} output reports were dropped: the device had not taken the previous "
        "ones (OUT queue of {} full)",
        k.out_queue_full, settings_->limits.out_queue);
  }
  if (k.drain_limit > logged_.drain_limit) {
    spdlog::warn("hid: {} ticks stopped draining after {} input reports", k.drain_limit, kMaxDrain);
  }
  logged_ = k;
}

std::string HidDevice::describe(const DeviceFault& fault) const {
  if (fault.fault_class == FaultClass::kDevice) {
    return "hid: the device reported a fault: " +
           (profile_ ? profile_->describe_status(fault.code) : std::to_string(fault.code));
  }
  const int e = static_cast<int>(fault.code);
  std::string s;
  if (e == ENOBUFS) {
    s = "hid: the device took no output report for " +
        std::to_string(settings_->limits.out_queue_full_fault) + " ticks in a row (OUT queue full)";
  } else if (e == ETIMEDOUT) {
    s = "hid: the device sent no report for longer than device.hid.liveness_ms (" +
        std::to_string(static_cast<long>(settings_->liveness_ms)) +
        " ms): its firmware is hung or the link is stalled";
  } else if (e == ENODEV || e == EIO || e == ESHUTDOWN || e == EPROTO) {
    // EPROTO: hidraw's write while usbhid tears the unplugged device down.
    s = std::string("hid: the device is gone (") + base::errno_text(e) + "): unplugged or reset?";
  } else {
    s = std::string("hid: the transport failed: ") + base::errno_text(e);
  }
  const std::string detail = transport_ ? transport_->last_error() : "";
  return detail.empty() ? s : s + " (" + detail + ")";
}

}  // namespace hapticd::drivers::hid
