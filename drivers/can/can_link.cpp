#include "drivers/can/can_link.h"

#include <cstring>

#include "base/clock.h"
#include "drivers/device.h"

namespace hapticd::drivers::can {

CanLink::CanLink(Opener open, std::string interface)
    : open_(std::move(open)), interface_(std::move(interface)) {}

const std::string& CanLink::description() const noexcept {
  return socket_ ? socket_->description() : interface_;
}

void CanLink::open() {
  socket_.emplace(open_());
  emergency_fd_.store(socket_->fd(), std::memory_order_release);
  // What waited before this configure (a transport kept across configures, a socketpair) is
  // older than anything configure may judge the drive by: an ODrive's heartbeat from before
  // an error, an SDO answer to an earlier question.
  CanSocket::Received rx;
  int error = 0;
  for (int i = 0; i < 1024; ++i) {
    const CanSocket::Io r = socket_->receive(rx, error);
    if (r != CanSocket::Io::kDone && r != CanSocket::Io::kMalformed) break;
  }
}

void CanLink::close() noexcept {
  emergency_fd_.store(-1, std::memory_order_release);
  socket_.reset();
}

void CanLink::send(const CanFrame& f, const char* what) {
  int error = 0;
  const CanSocket::Io r = socket_->send(f, error);
  if (r != CanSocket::Io::kDone) {
    throw DeviceError(
        "can: " + socket_->description() + ": sending " + what + " failed: " +
        (r == CanSocket::Io::kEmpty ? "the TX queue is full (ENOBUFS)" : std::strerror(error)));
  }
  count(CanCounter::kFramesSent);
}

void CanLink::send_quietly(const CanFrame& f) noexcept {
  if (!socket_) return;
  // Not the RT thread: a full queue is worth a short wait, since these are the frames that
  // switch the drive off.
  for (int attempt = 0; attempt < 20; ++attempt) {
    int error = 0;
    const CanSocket::Io r = socket_->send(f, error);
    if (r == CanSocket::Io::kDone) {
      count(CanCounter::kFramesSent);
      return;
    }
    if (r != CanSocket::Io::kEmpty) return;
    count(CanCounter::kTxQueueFull);
    socket_->wait_readable(1);
  }
}

bool CanLink::await(int timeout_ms, const std::function<bool(const CanFrame&)>& accept,
                    const std::function<void(const CanFrame&)>& other) {
  const std::int64_t deadline = base::monotonic_ms() + timeout_ms;
  CanSocket::Received rx;
  while (true) {
    int error = 0;
    const CanSocket::Io r = receive(rx, error);
    if (r == CanSocket::Io::kFailed) {
      throw DeviceError(
          "can: " + socket_->description() + ": " +
          (error == 0 ? std::string("the other end closed the connection") : std::strerror(error)));
    }
    if (r == CanSocket::Io::kMalformed) continue;
    if (r == CanSocket::Io::kDone) {
      if (rx.is_event) {
        const CanFaultKind kind = on_bus_event(rx.event);
        if (kind != CanFaultKind::kNone) {
          throw DeviceError(describe_bus_fault({kind, 0}, "can " + socket_->description()));
        }
        continue;
      }
      if (accept(rx.frame)) return true;
      if (other) other(rx.frame);
      continue;
    }
    const std::int64_t left = deadline - base::monotonic_ms();
    if (left <= 0) return false;
    socket_->wait_readable(static_cast<int>(left));
  }
}

void CanLink::wait_readable(int timeout_ms) const {
  if (socket_) socket_->wait_readable(timeout_ms);
}

void CanLink::set_emergency_frames(std::span<const CanFrame> frames) {
  emergency_count_ = 0;
  for (const CanFrame& f : frames) {
    if (emergency_count_ < emergency_.size())
      emergency_[emergency_count_++] = CanSocket::to_wire(f);
  }
}

void CanLink::emergency_stop() noexcept {
  const int fd = emergency_fd_.load(std::memory_order_acquire);
  if (fd >= 0) CanSocket::write_wire(fd, {emergency_.data(), emergency_count_});
}

CanSocket::Io CanLink::send_now(const CanFrame& f, int& error) noexcept {
  const CanSocket::Io r = socket_->send(f, error);
  if (r == CanSocket::Io::kDone) count(CanCounter::kFramesSent);
  if (r == CanSocket::Io::kEmpty) count(CanCounter::kTxQueueFull);
  return r;
}

CanSocket::Io CanLink::receive(CanSocket::Received& rx, int& error) noexcept {
  const CanSocket::Io r = socket_->receive(rx, error);
  if (r == CanSocket::Io::kDone) count(CanCounter::kFramesReceived);
  if (r == CanSocket::Io::kMalformed) count(CanCounter::kMalformed);
  return r;
}

CanFaultKind CanLink::on_bus_event(const BusEvent& e) noexcept {
  if (e.lost_arbitration) count(CanCounter::kLostArbitration);
  if (e.error_warning) count(CanCounter::kErrorWarnings);
  if (e.bus_error || e.protocol_violation || e.no_ack || e.tx_timeout || e.transceiver) {
    count(CanCounter::kBusErrors);
  }
  if (e.restarted) count(CanCounter::kControllerRestarts);
  // What stops frames from getting through is a transport fault; the rest is counted.
  if (e.bus_off) return CanFaultKind::kBusOff;
  if (e.error_passive) return CanFaultKind::kErrorPassive;
  if (e.rx_overflow) return CanFaultKind::kRxOverflow;
  return CanFaultKind::kNone;
}

std::string CanLink::anomalies() const {
  std::string out;
  for (const base::Counter& c : counters_) {
    if (c.kind() != base::CounterKind::kAnomaly || c.value() == 0) continue;
    out += (out.empty() ? "" : ", ") + std::to_string(c.value()) + " " + std::string(c.meaning());
  }
  return out;
}

}  // namespace hapticd::drivers::can
