#include "sim/peers/can/can_peer_base.h"

#include <sys/socket.h>

#include <cstring>
#include <stdexcept>
#include <string>

#include "base/clock.h"

namespace hapticd::sim {

using drivers::can::BusEvent;
using drivers::can::CanFrame;
using drivers::can::CanSocket;

CanPeerBase::CanPeerBase(const config::Config& cfg, CanSocket socket, bool realtime,
                         std::initializer_list<CanPeerFault> own_faults, const SharedJoint& joint)
    : settings_(drivers::can::can_settings(cfg)),
      period_s_(cfg.loop.sample_period_s()),
      axis_(joint.mechanism
                ? DriveAxis(cfg.device, cfg.loop.sample_period_s(), *joint.mechanism, joint.joint)
                : DriveAxis(cfg.device, cfg.loop.sample_period_s())),
      socket_(std::move(socket)),
      realtime_(realtime),
      can_faults_({CanPeerFault::kStopHeartbeat, CanPeerFault::kWrongLengthPdo,
                   CanPeerFault::kUnknownIds, CanPeerFault::kMalformedMessage}) {
  for (CanPeerFault f : own_faults) can_faults_.allow(f);
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

void CanPeerBase::service() {
  if (faults_.take(PeerFault::kDeviceFault)) apply_device_fault();
  if (faults_.take(PeerFault::kTransportFault) && !bus_failed_) {
    // The bus fails: the master's controller reports bus-off, and this device, off the bus
    // too, reacts as it does to losing its master; from now on nothing gets through.
    BusEvent off;
    off.bus_off = true;
    int error = 0;
    socket_.send_event(off, error);
    bus_failed_ = true;
    on_bus_lost();
  }
  if (can_faults_.take(CanPeerFault::kMalformedMessage)) {
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
  if (realtime_ && !bus_failed_) on_clock(base::monotonic_ns());
  publish();
}

}  // namespace hapticd::sim
