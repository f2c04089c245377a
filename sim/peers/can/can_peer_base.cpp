#include "sim/peers/can/can_peer_base.h"

#include <sys/socket.h>
#include <time.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace hapticd::sim {

using drivers::can::BusEvent;
using drivers::can::CanFrame;
using drivers::can::CanSocket;

CanPeerBase::CanPeerBase(const config::Config& cfg, CanSocket socket, bool realtime)
    : settings_(drivers::can::can_settings(cfg)),
      period_s_(cfg.loop.sample_period_s()),
      axis_(cfg.device, cfg.loop.sample_period_s()),
      socket_(std::move(socket)),
      realtime_(realtime) {}

std::int64_t CanPeerBase::now_ns() noexcept {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

bool CanPeerBase::inject(PeerFault fault) noexcept {
  switch (fault) {
    case PeerFault::kStopAnswering:
      stop_answering_.store(true);
      return true;
    case PeerFault::kSkipSequence:
      return false;  // neither a PDO nor Get_Encoder_Estimates carries a sequence number
    case PeerFault::kDeviceFault:
      device_fault_.store(true);
      return true;
    case PeerFault::kTransportFault:
      transport_fault_.store(true);
      return true;
  }
  return false;
}

bool CanPeerBase::inject_can(CanPeerFault fault) noexcept {
  switch (fault) {
    case CanPeerFault::kStopHeartbeat:
      stop_heartbeat_.store(true);
      return true;
    case CanPeerFault::kWrongLengthPdo:
      wrong_length_.store(true);
      return true;
    case CanPeerFault::kUnknownIds:
      unknown_ids_.store(true);
      return true;
    case CanPeerFault::kMalformedMessage:
      malformed_.store(true);
      return true;
    default:
      return false;
  }
}

void CanPeerBase::send(const CanFrame& f) {
  if (bus_failed_) return;
  int error = 0;
  const CanSocket::Io r = socket_.send(f, error);
  // The master closing its end is how a loopback run ends: nothing to say then.
  if (r == CanSocket::Io::kFailed && error != EPIPE && error != ECONNRESET) {
    throw std::runtime_error(std::string("simulated CAN device: send: ") + std::strerror(error));
  }
}

void CanPeerBase::publish() noexcept {
  applied_force_.store(axis_.held_force(), std::memory_order_release);
  output_on_.store(axis_.output_on(), std::memory_order_release);
}

void CanPeerBase::service() {
  if (take(device_fault_)) apply_device_fault();
  if (take(transport_fault_) && !bus_failed_) {
    // The bus fails: the master's controller reports bus-off, and this device, off the bus
    // too, reacts as it does to losing its master; from now on nothing gets through.
    BusEvent off;
    off.bus_off = true;
    int error = 0;
    socket_.send_event(off, error);
    bus_failed_ = true;
    on_bus_lost();
  }
  if (take(malformed_)) {
    const unsigned char junk[5] = {0xDE, 0xAD, 0xBE, 0xEF, 0x00};
    [[maybe_unused]] const ssize_t n = ::send(fd(), junk, sizeof junk, MSG_DONTWAIT | MSG_NOSIGNAL);
  }
  CanSocket::Received rx;
  while (true) {
    int error = 0;
    const CanSocket::Io r = socket_.receive(rx, error);
    if (r == CanSocket::Io::kEmpty || r == CanSocket::Io::kFailed) break;
    if (r == CanSocket::Io::kMalformed || rx.is_event) continue;
    received_.fetch_add(1, std::memory_order_relaxed);
    if (!bus_failed_) handle(rx.frame);
  }
  if (realtime_ && !bus_failed_) on_clock(now_ns());
  publish();
}

}  // namespace hapticd::sim
