#include "drivers/can/can_device.h"

#include <cmath>

namespace hapticd::drivers::can {
namespace {

// Frames handled per read at most: a tick's worth many times over, and a bound on the time a
// babbling bus can keep the RT thread in the drain.
constexpr int kMaxFramesPerDrain = 64;

std::unique_ptr<CanProfile> make_profile(const CanSettings& s, double period_s, int keeper_priority,
                                         CanLink& link) {
  if (s.profile == Profile::kOdrive) return make_odrive_profile(s, period_s, link);
  return make_cia402_profile(s, period_s, keeper_priority, link);
}

}  // namespace

CanDevice::CanDevice(const CanSettings& settings, double sample_period_s, CanLink::Opener open,
                     int keeper_priority)
    : tx_full_fault_ticks_(settings.tx_full_fault_ticks),
      link_(std::move(open), settings.interface),
      profile_(make_profile(settings, sample_period_s, keeper_priority, link_)),
      heartbeat_limit_ticks_(static_cast<std::uint32_t>(
          std::ceil(settings.heartbeat_timeout_ms * 1e-3 / sample_period_s - 1e-9))) {}

CanDevice::~CanDevice() { close(); }

DeviceInfo CanDevice::on_configure() {
  clear_pending();
  link_.open();
  return profile_->configure();
}

void CanDevice::on_enable() {
  clear_pending();
  profile_->enable();
  ticks_since_heartbeat_ = 0;  // the enable's own wait saw the drive alive
}

void CanDevice::on_disable() noexcept { profile_->disable({pending_.kind, fault().code}); }

void CanDevice::on_clear_fault() {
  if (!link_.is_open()) throw DeviceError("can: the transport is closed");
  clear_pending();
  profile_->clear_fault();
}

void CanDevice::on_close() noexcept {
  profile_->close();  // its threads write to the socket: they end first
  link_.close();
}

IoStatus CanDevice::on_read(std::span<PositionSample> samples) noexcept {
  PositionSample& out = samples.front();  // one joint
  const bool active = state() == DeviceState::kActive;
  bool fresh = false;
  if (drain(active, fresh) != IoStatus::kOk) return pending_status_;
  if (active && ++ticks_since_heartbeat_ > heartbeat_limit_ticks_) {
    return raise(CanFaultKind::kHeartbeatLost, ticks_since_heartbeat_);
  }
  if (!fresh) return IoStatus::kNoNewData;
  profile_->sample(out);
  return IoStatus::kOk;
}

IoStatus CanDevice::on_write(std::span<const double> forces) noexcept {
  const double force = forces.front();  // one joint
  for (const CanFrame& f : profile_->tick_frames(force)) {
    if (!send(f)) return pending_status_;
  }
  return end_tick_tx() ? IoStatus::kOk : pending_status_;
}

IoStatus CanDevice::drain(bool active, bool& fresh) noexcept {
  if (!link_.is_open()) return raise(CanFaultKind::kPeerClosed, 0);
  CanSocket::Received rx;
  for (int i = 0; i < kMaxFramesPerDrain && pending_status_ == IoStatus::kOk; ++i) {
    int error = 0;
    const CanSocket::Io r = link_.receive(rx, error);
    if (r == CanSocket::Io::kEmpty) break;
    if (r == CanSocket::Io::kFailed) {
      return raise(error == 0 ? CanFaultKind::kPeerClosed : CanFaultKind::kSocketError,
                   static_cast<std::uint32_t>(error));
    }
    if (r == CanSocket::Io::kMalformed) continue;  // counted by the link
    if (rx.is_event) {
      const CanFaultKind bus = link_.on_bus_event(rx.event);
      if (bus != CanFaultKind::kNone) raise(bus, 0);
      continue;
    }
    const FrameMeaning m = profile_->on_frame(rx, active);
    fresh = fresh || m.sample;
    if (m.heartbeat) ticks_since_heartbeat_ = 0;
    if (m.fault.kind != CanFaultKind::kNone) raise(m.fault.kind, m.fault.code);
  }
  return pending_status_;
}

bool CanDevice::send(const CanFrame& f) noexcept {
  if (!link_.is_open()) {
    raise(CanFaultKind::kPeerClosed, 0);
    return false;
  }
  int error = 0;
  const CanSocket::Io r = link_.send_now(f, error);
  if (r == CanSocket::Io::kEmpty) tx_full_this_tick_ = true;  // judged at the end of the tick
  if (r == CanSocket::Io::kDone || r == CanSocket::Io::kEmpty) return true;
  raise(CanFaultKind::kSocketError, static_cast<std::uint32_t>(error));
  return false;
}

bool CanDevice::end_tick_tx() noexcept {
  tx_full_streak_ = tx_full_this_tick_ ? tx_full_streak_ + 1 : 0;
  tx_full_this_tick_ = false;
  if (tx_full_streak_ >= tx_full_fault_ticks_) {
    raise(CanFaultKind::kTxQueueFull, static_cast<std::uint32_t>(tx_full_streak_));
    return false;
  }
  return true;
}

IoStatus CanDevice::raise(CanFaultKind kind, std::uint32_t code) noexcept {
  if (pending_status_ != IoStatus::kOk) return pending_status_;  // the first cause stands
  pending_ = {kind, code};
  set_fault_code(code);
  pending_status_ = is_transport(kind) ? IoStatus::kTransportFault : IoStatus::kDeviceFault;
  return pending_status_;
}

void CanDevice::clear_pending() noexcept {
  pending_status_ = IoStatus::kOk;
  pending_ = {};
  ticks_since_heartbeat_ = 0;
  tx_full_streak_ = 0;
  tx_full_this_tick_ = false;
}

std::string CanDevice::describe(const DeviceFault& f) const {
  const CanFault fault{pending_.kind, f.code};
  std::string s = profile_->describe(fault, link_.description());
  if (s.empty()) s = describe_bus_fault(fault, "can " + link_.description());
  const std::string seen = link_.anomalies();
  return seen.empty() ? s : s + " (also seen on the bus: " + seen + ")";
}

}  // namespace hapticd::drivers::can
