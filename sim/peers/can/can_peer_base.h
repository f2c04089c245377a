// What the simulated CAN devices (a CiA 402 drive, an ODrive axis) share: their end of the
// transport (a socketpair or a real interface, through the driver's own CanSocket), the
// simulated axis behind them, what the person holding the device feels (published for any
// thread: peer_state.h), a bus that can be made to fail, and CAN-specific faults beyond
// PeerFault. Each device decodes and answers with the driver's own pure codecs.
//
// Timing: in freerun (a paced loopback) the device's clock is its protocol trigger (SYNC,
// the encoder request), so a run is reproducible; in realtime (and on a real interface) its
// heartbeats and watchdogs also run on CLOCK_MONOTONIC, serviced every millisecond.
#pragma once

#include <atomic>
#include <cstdint>
#include <initializer_list>

#include "config/config.h"
#include "drivers/can/can_settings.h"
#include "drivers/can/can_socket.h"
#include "sim/mechanism.h"
#include "sim/peers/drive_axis.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_state.h"

namespace hapticd::sim {

// Faults only CAN can express, for the CAN tests (PeerFault covers the shared classes).
enum class CanPeerFault : std::uint8_t {
  kStopHeartbeat,     // heartbeats stop, everything else goes on
  kStopSdo,           // SDO requests (CiA 402) go unanswered
  kAbortSdo,          // the next SDO request (CiA 402) is aborted: 0x08000022, device state
  kWrongLengthPdo,    // the next cyclic answer has the wrong DLC
  kUnknownIds,        // frames with ids the driver does not expect, each tick
  kTruncatedEmcy,     // an EMCY of 2 bytes (CiA 402)
  kMalformedMessage,  // a message that is not one struct can_frame (socketpair only)
  kDisarm,            // ODrive 0.6: a short DC-bus dip disarms the axis: IDLE, no active error
                      // by its heartbeat, the reason only in Get_Error's disarm reason
};

// The joint of a mechanism a simulated drive moves with the other drives of its bus
// (can_bus_peer.h); `mechanism` null: an axis of its own.
struct SharedJoint {
  Mechanism* mechanism = nullptr;
  int joint = 0;
};

class CanPeerBase : public LoopbackPeer {
 public:
  void service() override;
  int fd() const noexcept override { return socket_.fd(); }
  int service_interval_ms() const noexcept override { return realtime_ ? 1 : -1; }
  double applied_force() const noexcept override { return felt_.force(); }
  bool output_on() const noexcept override { return felt_.on(); }
  const Plant& plant() const noexcept override { return axis_.plant(); }
  // kSkipSequence is refused: neither a PDO nor Get_Encoder_Estimates carries a sequence
  // number.
  bool inject(PeerFault fault) noexcept override { return faults_.inject(fault); }
  // Any thread. False when this device cannot produce it.
  bool inject_can(CanPeerFault fault) noexcept { return can_faults_.inject(fault); }
  // Any thread: frames this device received so far.
  std::uint64_t frames_received() const noexcept { return received_.load(); }

 protected:
  // `own_faults`: the CAN faults this device can produce beyond those every simulated CAN
  // device can (heartbeats stopped, a wrong-length answer, unknown ids, a malformed message).
  // `joint`: the joint of a mechanism shared with the bus's other drives it moves (null: an
  // axis of its own).
  CanPeerBase(const config::Config& cfg, drivers::can::CanSocket socket, bool realtime,
              std::initializer_list<CanPeerFault> own_faults, const SharedJoint& joint);

  // One frame from the master.
  virtual void handle(const drivers::can::CanFrame& f) = 0;
  // Realtime only: the device's own timers, at least every millisecond.
  virtual void on_clock(std::int64_t now_ns) = 0;
  // An injected PeerFault::kDeviceFault: the device's own way of reporting one.
  virtual void apply_device_fault() = 0;
  // The bus failed: the device's reaction to losing its master.
  virtual void on_bus_lost() = 0;

  void send(const drivers::can::CanFrame& f);
  // After each change of the axis: what any thread may read.
  void publish() noexcept { felt_.publish(axis_.held_force(), axis_.output_on()); }

  const drivers::can::CanSettings settings_;
  const double period_s_;
  DriveAxis axis_;
  drivers::can::CanSocket socket_;
  const bool realtime_;
  bool bus_failed_ = false;
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kDeviceFault,
                                PeerFault::kTransportFault};
  FaultFlags<CanPeerFault> can_faults_;

 private:
  FeltOutput felt_;
  std::atomic<std::uint64_t> received_{0};
};

}  // namespace hapticd::sim
