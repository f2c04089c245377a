#include "drivers/can/can_device_base.h"

#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace hapticd::drivers::can {
namespace {

// Frames handled per read at most: a tick's worth many times over, and a bound on the time a
// babbling bus can keep the RT thread in the drain.
constexpr int kMaxFramesPerDrain = 64;

void bump(std::atomic<std::uint64_t>& c) noexcept { c.fetch_add(1, std::memory_order_relaxed); }

}  // namespace

std::int64_t CanDeviceBase::now_ms() noexcept {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1'000'000;
}

std::string CanDeviceBase::hex(std::uint32_t v, int digits) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%0*X", digits, v);
  return buf;
}

CanDeviceBase::CanDeviceBase(const CanSettings& settings, double sample_period_s, Opener open)
    : settings_(settings),
      period_s_(sample_period_s),
      open_(std::move(open)),
      heartbeat_limit_ticks_(static_cast<std::uint32_t>(
          std::ceil(settings.heartbeat_timeout_ms * 1e-3 / sample_period_s - 1e-9))) {}

void CanDeviceBase::open_transport() {
  socket_.emplace(open_());
  emergency_fd_.store(socket_->fd(), std::memory_order_release);
  clear_pending();
  // What waited before this configure (a transport kept across configures, a socketpair) is
  // older than anything configure may judge the device by: an ODrive's heartbeat from before
  // an error, an SDO answer to an earlier question.
  CanSocket::Received rx;
  int error = 0;
  for (int i = 0; i < 1024; ++i) {
    const CanSocket::Io r = socket_->receive(rx, error);
    if (r != CanSocket::Io::kDone && r != CanSocket::Io::kMalformed) break;
  }
}

void CanDeviceBase::close_transport() noexcept {
  emergency_fd_.store(-1, std::memory_order_release);
  socket_.reset();
}

void CanDeviceBase::send_or_throw(const CanFrame& f, const char* what) {
  int error = 0;
  const CanSocket::Io r = socket_->send(f, error);
  if (r != CanSocket::Io::kDone) {
    throw DeviceError(
        "can: " + socket_->description() + ": sending " + what + " failed: " +
        (r == CanSocket::Io::kEmpty ? "the TX queue is full (ENOBUFS)" : std::strerror(error)));
  }
  bump(counters_.frames_sent);
}

void CanDeviceBase::send_quietly(const CanFrame& f) noexcept {
  if (!socket_) return;
  // Not the RT thread: a full queue is worth a short wait, since these are the frames that
  // switch the drive off.
  for (int attempt = 0; attempt < 20; ++attempt) {
    int error = 0;
    const CanSocket::Io r = socket_->send(f, error);
    if (r == CanSocket::Io::kDone) {
      bump(counters_.frames_sent);
      return;
    }
    if (r != CanSocket::Io::kEmpty) return;
    bump(counters_.tx_queue_full);
    socket_->wait_readable(1);
  }
}

bool CanDeviceBase::await(int timeout_ms, const std::function<bool(const CanFrame&)>& accept,
                          const std::function<void(const CanFrame&)>& other) {
  const std::int64_t deadline = now_ms() + timeout_ms;
  CanSocket::Received rx;
  while (true) {
    int error = 0;
    const CanSocket::Io r = socket_->receive(rx, error);
    if (r == CanSocket::Io::kFailed) {
      throw DeviceError(
          "can: " + socket_->description() + ": " +
          (error == 0 ? std::string("the other end closed the connection") : std::strerror(error)));
    }
    if (r == CanSocket::Io::kMalformed) {
      bump(counters_.malformed_messages);
      continue;
    }
    if (r == CanSocket::Io::kDone) {
      bump(counters_.frames_received);
      if (rx.is_event) {
        on_bus_event(rx.event);
        if (pending_status_ != IoStatus::kOk) {
          throw DeviceError("can: " + socket_->description() + ": " +
                            describe_transport({FaultClass::kTransport, 0}));
        }
        continue;
      }
      if (accept(rx.frame)) return true;
      if (other) other(rx.frame);
      continue;
    }
    const std::int64_t left = deadline - now_ms();
    if (left <= 0) return false;
    socket_->wait_readable(static_cast<int>(left));
  }
}

void CanDeviceBase::set_emergency_frames(std::initializer_list<CanFrame> frames) {
  emergency_count_ = 0;
  for (const CanFrame& f : frames) {
    if (emergency_count_ < emergency_.size())
      emergency_[emergency_count_++] = CanSocket::to_wire(f);
  }
}

void CanDeviceBase::emergency_stop() noexcept {
  const int fd = emergency_fd_.load(std::memory_order_acquire);
  if (fd >= 0) CanSocket::write_wire(fd, {emergency_.data(), emergency_count_});
}

IoStatus CanDeviceBase::raise(CanFaultKind kind, std::uint32_t code) noexcept {
  if (pending_status_ != IoStatus::kOk) return pending_status_;  // the first cause stands
  const bool transport = kind == CanFaultKind::kSocketError || kind == CanFaultKind::kPeerClosed ||
                         kind == CanFaultKind::kBusOff || kind == CanFaultKind::kErrorPassive ||
                         kind == CanFaultKind::kRxOverflow || kind == CanFaultKind::kTxQueueFull;
  kind_ = kind;
  set_fault_code(code);
  pending_status_ = transport ? IoStatus::kTransportFault : IoStatus::kDeviceFault;
  return pending_status_;
}

void CanDeviceBase::clear_pending() noexcept {
  pending_status_ = IoStatus::kOk;
  kind_ = CanFaultKind::kNone;
  ticks_since_heartbeat_ = 0;
  tx_full_streak_ = 0;
  tx_full_this_tick_ = false;
}

void CanDeviceBase::on_bus_event(const BusEvent& e) noexcept {
  if (e.lost_arbitration) bump(counters_.lost_arbitration);
  if (e.error_warning) bump(counters_.error_warnings);
  if (e.bus_error || e.protocol_violation || e.no_ack || e.tx_timeout || e.transceiver) {
    bump(counters_.bus_errors);
  }
  if (e.restarted) bump(counters_.controller_restarts);
  // What stops frames from getting through is a transport fault; the rest is counted.
  if (e.bus_off) {
    raise(CanFaultKind::kBusOff, 0);
  } else if (e.error_passive) {
    raise(CanFaultKind::kErrorPassive, 0);
  } else if (e.rx_overflow) {
    raise(CanFaultKind::kRxOverflow, 0);
  }
}

IoStatus CanDeviceBase::drain() noexcept {
  if (!socket_) return raise(CanFaultKind::kPeerClosed, 0);
  CanSocket::Received rx;
  for (int i = 0; i < kMaxFramesPerDrain && pending_status_ == IoStatus::kOk; ++i) {
    int error = 0;
    const CanSocket::Io r = socket_->receive(rx, error);
    if (r == CanSocket::Io::kEmpty) break;
    if (r == CanSocket::Io::kFailed) {
      return raise(error == 0 ? CanFaultKind::kPeerClosed : CanFaultKind::kSocketError,
                   static_cast<std::uint32_t>(error));
    }
    if (r == CanSocket::Io::kMalformed) {
      bump(counters_.malformed_messages);
      continue;
    }
    bump(counters_.frames_received);
    if (rx.is_event) {
      on_bus_event(rx.event);
    } else {
      on_frame(rx);
    }
  }
  return pending_status_;
}

bool CanDeviceBase::send_rt(const CanFrame& f) noexcept {
  if (!socket_) {
    raise(CanFaultKind::kPeerClosed, 0);
    return false;
  }
  int error = 0;
  const CanSocket::Io r = socket_->send(f, error);
  if (r == CanSocket::Io::kDone) {
    bump(counters_.frames_sent);
    return true;
  }
  if (r == CanSocket::Io::kEmpty) {
    bump(counters_.tx_queue_full);
    tx_full_this_tick_ = true;
    return true;  // judged at the end of the tick
  }
  raise(CanFaultKind::kSocketError, static_cast<std::uint32_t>(error));
  return false;
}

bool CanDeviceBase::end_tick_tx() noexcept {
  tx_full_streak_ = tx_full_this_tick_ ? tx_full_streak_ + 1 : 0;
  tx_full_this_tick_ = false;
  if (tx_full_streak_ >= settings_.tx_full_fault_ticks) {
    raise(CanFaultKind::kTxQueueFull, static_cast<std::uint32_t>(tx_full_streak_));
    return false;
  }
  return true;
}

std::string CanDeviceBase::describe_transport(const DeviceFault& f) const {
  const std::string where = "can " + (socket_ ? socket_->description() : settings_.interface);
  switch (kind_) {
    case CanFaultKind::kSocketError:
      return where + ": the socket failed: " + std::strerror(static_cast<int>(f.code)) +
             " (errno " + std::to_string(f.code) + ")";
    case CanFaultKind::kPeerClosed:
      return where + ": the other end of the connection went away";
    case CanFaultKind::kBusOff:
      return where +
             ": the CAN controller went bus-off (too many errors: wiring, termination, "
             "bitrate, or a node that is off); nothing reaches the drive";
    case CanFaultKind::kErrorPassive:
      return where + ": the CAN controller went error-passive (error counter above 127)";
    case CanFaultKind::kRxOverflow:
      return where + ": the CAN controller lost received frames (overflow)";
    case CanFaultKind::kTxQueueFull:
      return where + ": the TX queue refused frames (ENOBUFS) " + std::to_string(f.code) +
             " ticks in a row: the bus does not carry what the loop sends";
    default:
      return where + ": transport fault";
  }
}

std::string CanDeviceBase::counter_summary() const {
  std::string out;
  const auto add = [&](const std::atomic<std::uint64_t>& c, const char* name) {
    const std::uint64_t n = c.load(std::memory_order_relaxed);
    if (n != 0) out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + name;
  };
  add(counters_.malformed_messages, "malformed messages");
  add(counters_.wrong_length, "frames of the wrong length");
  add(counters_.unknown_ids, "frames with unexpected ids");
  add(counters_.tx_queue_full, "TX queue full (ENOBUFS)");
  add(counters_.lost_arbitration, "lost arbitrations");
  add(counters_.error_warnings, "error warnings");
  add(counters_.bus_errors, "bus errors");
  add(counters_.controller_restarts, "controller restarts");
  add(counters_.emcy_resets, "EMCY error resets");
  add(counters_.sdo_aborts, "SDO aborts");
  add(counters_.over_vel_limit,
      "ticks above the axis's torque-mode velocity limit (controller.config.vel_limit: the "
      "firmware braked)");
  add(counters_.internal_limit,
      "ticks with the drive's internal limit active (statusword bit 11: it limited the torque "
      "itself)");
  add(counters_.unsolicited_estimates,
      "encoder estimates the axis sent by itself (not answers; its encoder rate is not 0)");
  return out;
}

}  // namespace hapticd::drivers::can
