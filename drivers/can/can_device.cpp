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
      joints_(settings.nodes.size()),
      link_(std::move(open), settings.interface),
      profile_(make_profile(settings, sample_period_s, keeper_priority, link_)),
      heartbeat_limit_ticks_(static_cast<std::uint32_t>(
          std::ceil(settings.heartbeat_timeout_ms * 1e-3 / sample_period_s - 1e-9))) {}

CanDevice::~CanDevice() { close(); }

DeviceInfo CanDevice::on_configure() {
  clear_pending();
  link_.open();
  DeviceInfo info = profile_->configure();
  info.joints = joints_;
  return info;
}

void CanDevice::on_enable() {
  clear_pending();
  profile_->enable();
  ticks_since_heartbeat_.fill(0);  // the enable's own waits saw every drive alive
}

void CanDevice::on_disable() noexcept {
  profile_->disable({pending_.kind, fault().code, pending_.joint});
}

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
  const bool active = state() == DeviceState::kActive;
  unsigned fresh = 0;  // bit j: joint j's node sent a sample this tick
  if (drain(active, fresh) != IoStatus::kOk) return pending_status_;
  for (std::size_t j = 0; active && j < joints_; ++j) {
    if (++ticks_since_heartbeat_[j] > heartbeat_limit_ticks_) {
      return raise(
          {CanFaultKind::kHeartbeatLost, ticks_since_heartbeat_[j], static_cast<std::uint8_t>(j)});
    }
  }
  // A tick is fresh when every node's sample is (they answer the same SYNC or request).
  if (fresh != (1u << joints_) - 1u) return IoStatus::kNoNewData;
  for (std::size_t j = 0; j < joints_; ++j) profile_->sample(j, samples[j]);
  return IoStatus::kOk;
}

IoStatus CanDevice::on_write(std::span<const double> forces) noexcept {
  for (const CanFrame& f : profile_->tick_frames(forces)) {
    if (!send(f)) return pending_status_;
  }
  return end_tick_tx() ? IoStatus::kOk : pending_status_;
}

IoStatus CanDevice::drain(bool active, unsigned& fresh) noexcept {
  if (!link_.is_open()) return raise({CanFaultKind::kPeerClosed, 0});
  CanSocket::Received rx;
  for (int i = 0; i < kMaxFramesPerDrain && pending_status_ == IoStatus::kOk; ++i) {
    int error = 0;
    const CanSocket::Io r = link_.receive(rx, error);
    if (r == CanSocket::Io::kEmpty) break;
    if (r == CanSocket::Io::kFailed) {
      return raise({error == 0 ? CanFaultKind::kPeerClosed : CanFaultKind::kSocketError,
                    static_cast<std::uint32_t>(error)});
    }
    if (r == CanSocket::Io::kMalformed) continue;  // counted by the link
    if (rx.is_event) {
      const CanFaultKind bus = link_.on_bus_event(rx.event);
      if (bus != CanFaultKind::kNone) raise({bus, 0});
      continue;
    }
    const FrameMeaning m = profile_->on_frame(rx, active);
    if (m.sample) fresh |= 1u << m.joint;
    if (m.heartbeat) ticks_since_heartbeat_[m.joint] = 0;
    if (m.fault.kind != CanFaultKind::kNone) raise(m.fault);
  }
  return pending_status_;
}

bool CanDevice::send(const CanFrame& f) noexcept {
  if (!link_.is_open()) {
    raise({CanFaultKind::kPeerClosed, 0});
    return false;
  }
  int error = 0;
  const CanSocket::Io r = link_.send_now(f, error);
  if (r == CanSocket::Io::kEmpty) tx_full_this_tick_ = true;  // judged at the end of the tick
  if (r == CanSocket::Io::kDone || r == CanSocket::Io::kEmpty) return true;
  raise({CanFaultKind::kSocketError, static_cast<std::uint32_t>(error)});
  return false;
}

bool CanDevice::end_tick_tx() noexcept {
  tx_full_streak_ = tx_full_this_tick_ ? tx_full_streak_ + 1 : 0;
  tx_full_this_tick_ = false;
  if (tx_full_streak_ >= tx_full_fault_ticks_) {
    raise({CanFaultKind::kTxQueueFull, static_cast<std::uint32_t>(tx_full_streak_)});
    return false;
  }
  return true;
}

IoStatus CanDevice::raise(CanFault fault) noexcept {
  if (pending_status_ != IoStatus::kOk) return pending_status_;  // the first cause stands
  pending_ = fault;
  set_fault_code(fault.code);
  pending_status_ = is_transport(fault.kind) ? IoStatus::kTransportFault : IoStatus::kDeviceFault;
  return pending_status_;
}

void CanDevice::clear_pending() noexcept {
  pending_status_ = IoStatus::kOk;
  pending_ = {};
  ticks_since_heartbeat_.fill(0);
  tx_full_streak_ = 0;
  tx_full_this_tick_ = false;
}

std::string CanDevice::describe(const DeviceFault& f) const {
  const CanFault fault{pending_.kind, f.code, pending_.joint};
  std::string s = profile_->describe(fault, link_.description());
  if (s.empty()) s = describe_bus_fault(fault, "can " + link_.description());
  const std::string seen = link_.anomalies();
  return seen.empty() ? s : s + " (also seen on the bus: " + seen + ")";
}

}  // namespace hapticd::drivers::can
