// The simulated CiA 402 drive's cyclic side: frames dispatched, SYNC (plant step, RPDO
// applied, TPDOs sent), heartbeats, and the watchdogs on its own clock.
#include <algorithm>
#include <cmath>

#include "base/clock.h"
#include "sim/peers/can/cia402_peer.h"

namespace hapticd::sim {
namespace {

using drivers::can::CanFrame;
using drivers::can::canopen::NmtState;
using drivers::can::cia402::PowerState;
namespace canopen = drivers::can::canopen;
namespace cia402 = drivers::can::cia402;

// The SYNC watchdog: this many communication cycles without SYNC is a lost master (generous:
// a loaded host's wake-up jitter must not trip it, a killed process must).
constexpr std::int64_t kSyncLossCycles = 20;

}  // namespace

std::int32_t Cia402Peer::mapped_value(std::uint16_t index) noexcept {
  switch (index) {
    case 0x6041:
      return cia402::encode_statusword(power_.load());
    case 0x6064:
      return position_units();
    case 0x606C:
      return static_cast<std::int32_t>(
          std::lround(axis_.velocity() / settings_.nodes.front().position_per_unit));
    case 0x6071:
      return target_torque_;
    case 0x6040:
      return controlword_;
    default:
      return 0;
  }
}

void Cia402Peer::send_tpdo(std::uint16_t comm, std::uint16_t map) {
  const std::uint32_t cob = object(comm, 1);
  const std::uint32_t type = object(comm, 2);
  if ((cob & cia402::kCobIdInvalid) != 0 || type == 0 || type > 240) return;
  if (syncs_ % type != 0) return;
  CanFrame f = drivers::can::make_frame(cob & drivers::can::kSffMask, 0);
  int at = 0;
  for (std::uint8_t s = 1; s <= object(map, 0) && s <= 8; ++s) {
    const std::uint32_t e = object(map, s);
    const int bytes = static_cast<int>((e & 0xFF) / 8);
    if (at + bytes > 8) return;
    const auto v = static_cast<std::uint32_t>(mapped_value(static_cast<std::uint16_t>(e >> 16)));
    for (int b = 0; b < bytes; ++b) f.data[at + b] = static_cast<std::uint8_t>(v >> (8 * b));
    at += bytes;
  }
  f.len = static_cast<std::uint8_t>(at);
  if (map == 0x1A00 && can_faults_.take(CanPeerFault::kWrongLengthPdo))
    f.len = static_cast<std::uint8_t>(at - 1);
  send(f);
}

void Cia402Peer::heartbeat() {
  if (!can_faults_.active(CanPeerFault::kStopHeartbeat))
    send(canopen::heartbeat_frame(node_, nmt_));
}

void Cia402Peer::on_sync() {
  if (nmt_ != NmtState::kOperational) return;
  // The plant has run one period since the last SYNC with the torque held then; the RPDO that
  // came since takes effect now, and the drive samples its position for the TPDOs.
  if (synced_) axis_.step();
  synced_ = true;
  ++syncs_;
  if (pending_rpdo_) {
    pending_rpdo_ = false;
    target_torque_ = pending_torque_;
    set_controlword(pending_cw_);
  }
  if (!faults_.active(PeerFault::kStopAnswering)) {
    for (std::uint16_t i = 0; i < 4; ++i) {
      send_tpdo(static_cast<std::uint16_t>(0x1800 + i), static_cast<std::uint16_t>(0x1A00 + i));
    }
  }
  if (can_faults_.take(CanPeerFault::kTruncatedEmcy)) {
    CanFrame e = canopen::emcy_frame(node_, 0x1000, 0x01);
    e.len = 2;
    send(e);
  }
  if (can_faults_.active(CanPeerFault::kUnknownIds)) send(drivers::can::make_frame(0x7E5, 3));
  const std::uint32_t producer_ms = object(0x1017, 0);
  if (!realtime_ && producer_ms > 0) {
    const auto every =
        static_cast<std::uint64_t>(std::max(1.0, std::round(producer_ms * 1e-3 / period_s_)));
    if (syncs_ % every == 0) heartbeat();
  }
}

void Cia402Peer::handle(const CanFrame& f) {
  if (f.extended) return;
  const std::uint32_t master = (object(0x1016, 1) >> 16) & 0x7F;
  if (const auto c = canopen::decode_nmt(f, node_)) {
    on_nmt(*c);
  } else if (f.id == canopen::kSyncId && f.len == 0) {
    last_sync_ns_ = realtime_ ? base::monotonic_ns() : 0;
    on_sync();
  } else if (f.id == canopen::kSdoRxBase + node_) {
    on_sdo(f);
  } else if (f.id == (object(0x1400, 1) & drivers::can::kSffMask) &&
             (object(0x1400, 1) & cia402::kCobIdInvalid) == 0 && nmt_ == NmtState::kOperational) {
    on_rpdo(f);
  } else if (master != 0 && f.id == canopen::kHeartbeatBase + master) {
    if (realtime_) last_master_heartbeat_ns_ = base::monotonic_ns();
  }
}

void Cia402Peer::on_clock(std::int64_t now) {
  const std::uint32_t producer_ms = object(0x1017, 0);
  if (producer_ms > 0 && now - last_heartbeat_ns_ >= producer_ms * 1'000'000LL) {
    last_heartbeat_ns_ = now;
    heartbeat();
  }
  // The drive's watchdogs on hapticd: its heartbeat (0x1016, watched from the first one on)
  // and, while operation is enabled, the SYNC cycle (0x1006).
  const std::uint32_t consumer_ms = object(0x1016, 1) & 0xFFFF;
  if (consumer_ms > 0 && last_master_heartbeat_ns_ != 0 &&
      now - last_master_heartbeat_ns_ > consumer_ms * 1'000'000LL) {
    last_master_heartbeat_ns_ = 0;
    lose_master(0x8130);  // life guard / heartbeat error
  }
  // The SYNC watch is the manufacturer's; this drive's is never stricter than the silence its
  // master said it tolerates (0x1016:1), so a configuration's one tolerance for a stalled
  // master (drive_watchdog_ms) holds for both watchdogs.
  const std::uint32_t cycle_us = object(0x1006, 0);
  const std::int64_t sync_window_ns =
      std::max(kSyncLossCycles * cycle_us * 1000LL, consumer_ms * 1'000'000LL);
  if (cycle_us > 0 && last_sync_ns_ != 0 && nmt_ == NmtState::kOperational &&
      power_.load() == PowerState::kOperationEnabled && now - last_sync_ns_ > sync_window_ns) {
    last_sync_ns_ = 0;
    lose_master(0x8100);  // communication: SYNC lost
  }
}

}  // namespace hapticd::sim
