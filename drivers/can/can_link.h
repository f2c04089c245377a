// The CAN device's end of the bus (docs/drivers/can.md): the socket's lifetime, every frame in
// and out counted, what the controller reports decoded and counted, the waits of the start-up
// and shut-down sequences, and the prebuilt frames of the emergency stop. CanDevice owns one;
// its profile (can_profile.h) speaks through it. The counters are the driver's
// Device::counters, readable from any thread.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>

#include "base/counters.h"
#include "drivers/can/can_fault.h"
#include "drivers/can/can_socket.h"

namespace hapticd::drivers::can {

// The driver's counters, in the order Device::counters lists them.
enum class CanCounter : std::uint8_t {
  kFramesReceived,
  kFramesSent,
  kMalformed,
  kWrongLength,
  kUnknownIds,
  kTxQueueFull,
  kLostArbitration,
  kErrorWarnings,
  kBusErrors,
  kControllerRestarts,
  kEmcyResets,
  kSdoAborts,
  kOverVelLimit,
  kInternalLimit,
  kUnsolicitedEstimates,
  kEmcysInStop,
  kCount
};

class CanLink {
 public:
  // Opens the transport at each configure; the loopback passes one that adopts its
  // socketpair end. `interface` names the bus while no socket is open.
  using Opener = std::function<CanSocket()>;
  CanLink(Opener open, std::string interface);
  CanLink(const CanLink&) = delete;
  CanLink& operator=(const CanLink&) = delete;

  // Not RT-safe. Opens the socket and drops what waited on it.
  void open();
  // Not RT-safe, never throws.
  void close() noexcept;
  bool is_open() const noexcept { return socket_.has_value(); }
  // The socket's description ("vcan0", "loopback"), or the interface while closed.
  const std::string& description() const noexcept;
  // The open socket's descriptor, for a thread that keeps a drive fed (PeriodicSender).
  int fd() const noexcept { return socket_ ? socket_->fd() : -1; }

  // --- not RT-safe: the start-up and shut-down sequences ---
  // Sends or throws DeviceError naming `what`.
  void send(const CanFrame& f, const char* what);
  // Best effort (a stop, a close): errors ignored, a full queue waited for briefly.
  void send_quietly(const CanFrame& f) noexcept;
  // Receives frames until `accept` returns true (true) or timeout_ms passes (false). Every
  // other frame goes to `other` (nullptr: dropped). Throws DeviceError if the transport fails
  // or the controller reports a bus fault.
  bool await(int timeout_ms, const std::function<bool(const CanFrame&)>& accept,
             const std::function<void(const CanFrame&)>& other);
  void wait_readable(int timeout_ms) const;
  // The frames emergency_stop() writes (at most kMaxEmergencyFrames: each node's stop), built
  // now.
  static constexpr std::size_t kMaxEmergencyFrames = 8;
  void set_emergency_frames(std::span<const CanFrame> frames);
  // Async-signal-safe: write(2) of those frames on the open socket.
  void emergency_stop() noexcept;

  // RT-safe: called every tick. One frame out, counted as sent or as refused by a full TX
  // queue (kEmpty). The socket is open.
  CanSocket::Io send_now(const CanFrame& f, int& error) noexcept;
  // RT-safe: called every tick. The next frame or bus event in, counted (malformed messages
  // too). The socket is open.
  CanSocket::Io receive(CanSocket::Received& rx, int& error) noexcept;
  // RT-safe: called every tick. Counts what the controller reported; the kind of fault when
  // the report means frames no longer get through (bus-off, error passive, RX overflow),
  // kNone when it is only counted.
  CanFaultKind on_bus_event(const BusEvent& e) noexcept;
  // RT-safe: called every tick.
  void count(CanCounter c) noexcept { counters_[static_cast<std::size_t>(c)].add(); }

  // Any thread.
  std::span<const base::Counter> counters() const noexcept { return counters_; }
  // Not RT-safe. "1 frames of the wrong length (...), 2 SDO aborts": the anomalies that are
  // not zero, "" when there are none.
  std::string anomalies() const;

 private:
  Opener open_;
  std::string interface_;
  std::optional<CanSocket> socket_;
  std::array<WireFrame, kMaxEmergencyFrames> emergency_{};
  std::size_t emergency_count_ = 0;
  std::atomic<int> emergency_fd_{-1};
  using K = base::CounterKind;
  std::array<base::Counter, static_cast<std::size_t>(CanCounter::kCount)> counters_{{
      {"frames_received", K::kCount, "frames and controller reports received"},
      {"frames_sent", K::kCount, "frames sent"},
      {"malformed_messages", K::kAnomaly, "malformed messages (not one struct can_frame)"},
      {"wrong_length", K::kAnomaly, "frames of the wrong length (a known id)"},
      {"unknown_ids", K::kAnomaly, "frames with unexpected ids"},
      {"tx_queue_full", K::kAnomaly, "frames the full TX queue refused (ENOBUFS)"},
      {"lost_arbitration", K::kAnomaly, "lost arbitrations"},
      {"error_warnings", K::kAnomaly, "error warnings (an error counter above 95)"},
      {"bus_errors", K::kAnomaly, "bus errors (bit, stuff, CRC, ACK, TX time-out, transceiver)"},
      {"controller_restarts", K::kAnomaly, "controller restarts after bus-off"},
      {"emcy_resets", K::kCount, "EMCY error resets (the drive's error cleared)"},
      {"sdo_aborts", K::kAnomaly, "SDO aborts"},
      {"over_vel_limit", K::kAnomaly,
       "ticks above the axis's torque-mode velocity limit (controller.config.vel_limit: the "
       "firmware braked)"},
      {"internal_limit", K::kAnomaly,
       "ticks with the drive's internal limit active (statusword bit 11: it limited the torque "
       "itself)"},
      {"unsolicited_estimates", K::kAnomaly,
       "encoder estimates the axis sent by itself (not answers; its encoder rate is not 0)"},
      {"emcys_in_stop", K::kAnomaly,
       "EMCYs a drive sent while the stop switched it off (0x8100: a SYNC came late)"},
  }};
};

}  // namespace hapticd::drivers::can
