// What the two CAN devices (CiA 402, ODrive) share: the transport's lifetime, the RT drain of
// everything the socket queued (bus events decoded, malformed messages counted and named),
// sending that never blocks (a full TX queue is counted, and faults only when it persists),
// the heartbeat watch counted in ticks, the fault kinds and their sentences, counters readable
// off the RT thread, and the prebuilt frames of the emergency stop.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "drivers/can/can_settings.h"
#include "drivers/can/can_socket.h"
#include "drivers/device.h"

namespace hapticd::drivers::can {

// Counters of everything unusual the transport and the protocol met; any thread may read them.
struct CanCounters {
  std::atomic<std::uint64_t> frames_received{0};
  std::atomic<std::uint64_t> frames_sent{0};
  std::atomic<std::uint64_t> malformed_messages{0};  // not one struct can_frame
  std::atomic<std::uint64_t> wrong_length{0};        // a known id with the wrong DLC
  std::atomic<std::uint64_t> unknown_ids{0};         // an id the profile does not expect
  std::atomic<std::uint64_t> tx_queue_full{0};       // ENOBUFS / EAGAIN on send
  std::atomic<std::uint64_t> lost_arbitration{0};
  std::atomic<std::uint64_t> error_warnings{0};
  std::atomic<std::uint64_t> bus_errors{0};  // bit/stuff/CRC/ack/timeout reports
  std::atomic<std::uint64_t> controller_restarts{0};
  std::atomic<std::uint64_t> emcy_resets{0};  // EMCY 0x0000: the drive's error cleared
  std::atomic<std::uint64_t> sdo_aborts{0};
  // Forces the drive applied that hapticd did not command, and messages it did not ask for.
  std::atomic<std::uint64_t> over_vel_limit{0};  // ODrive: ticks above controller.config.vel_limit
  std::atomic<std::uint64_t> internal_limit{0};  // CiA 402: ticks with statusword bit 11
  std::atomic<std::uint64_t> unsolicited_estimates{0};  // ODrive: cyclic estimates, not answers
};

// Why a CAN device latched (its describe() sentence); the fault code holds the detail.
enum class CanFaultKind : std::uint8_t {
  kNone,
  kSocketError,       // code: errno
  kPeerClosed,        // the socketpair's other end went away
  kBusOff,            // the controller left the bus
  kErrorPassive,      // the controller's error counters passed 127
  kRxOverflow,        // frames were lost in the controller
  kTxQueueFull,       // code: ticks in a row the queue refused a frame
  kHeartbeatLost,     // code: ticks without a heartbeat
  kEmcy,              // code: error register << 16 | EMCY error code
  kEmcyTruncated,     // code: the frame's length
  kStatuswordFault,   // code: statusword
  kLeftOperation,     // code: statusword (enabled -> something else)
  kNmtStateChanged,   // code: the NMT state the heartbeat reported
  kAxisError,         // code: ODrive axis error
  kAxisStateChanged,  // code: ODrive axis state
};

class CanDeviceBase : public Device {
 public:
  std::string_view driver_name() const noexcept override { return "can"; }
  // Async-signal-safe: write(2) of the profile's prebuilt zero-torque and disable frames.
  void emergency_stop() noexcept override;
  const CanCounters& can_counters() const noexcept { return counters_; }
  std::vector<std::string> notices() const override { return notices_; }
  // Not RT-safe: "3 wrong-length frames, 1 unknown id" (empty when nothing was unusual).
  std::string counter_summary() const;

 protected:
  // Opens the transport at configure; the loopback passes one that adopts its socketpair end.
  using Opener = std::function<CanSocket()>;
  CanDeviceBase(const CanSettings& settings, double sample_period_s, Opener open);

  // --- non-RT helpers for configure, enable, disable, clear_fault ---
  void open_transport();
  void close_transport() noexcept;
  // Sends or throws DeviceError naming `what`.
  void send_or_throw(const CanFrame& f, const char* what);
  // Best effort (disable, close): errors ignored.
  void send_quietly(const CanFrame& f) noexcept;
  // Receives frames until `accept` returns true (true) or timeout_ms passes (false). Every
  // other frame goes to `other` (nullptr: dropped). Throws DeviceError if the transport fails.
  bool await(int timeout_ms, const std::function<bool(const CanFrame&)>& accept,
             const std::function<void(const CanFrame&)>& other);
  void set_emergency_frames(std::initializer_list<CanFrame> frames);

  // --- RT helpers (RT-safe: called every tick) ---
  // Drains the socket; each frame goes to the profile's on_frame. Returns kOk when done, or the
  // fault status (after set_fault_code) when the transport or the profile faulted.
  IoStatus drain() noexcept;
  virtual void on_frame(const CanSocket::Received& rx) noexcept = 0;
  // Sends on the RT thread: a full queue is counted and faults after tx_full_fault_ticks.
  // Returns false when the device must fault (the fault is recorded).
  bool send_rt(const CanFrame& f) noexcept;
  // Call once per write(): closes the tick's TX-queue accounting. False when it faults.
  bool end_tick_tx() noexcept;
  // Records the first fault of this tick; the status the hook returns.
  IoStatus raise(CanFaultKind kind, std::uint32_t code) noexcept;
  IoStatus pending_fault() const noexcept { return pending_status_; }
  void clear_pending() noexcept;
  // Heartbeat watch: a heartbeat arrived / a tick passed. True once it has been silent for
  // heartbeat_timeout_ms worth of ticks.
  void heartbeat_seen() noexcept { ticks_since_heartbeat_ = 0; }
  bool heartbeat_lost() noexcept { return ++ticks_since_heartbeat_ > heartbeat_limit_ticks_; }
  std::uint32_t ticks_since_heartbeat() const noexcept { return ticks_since_heartbeat_; }

  // CLOCK_MONOTONIC in ms, for the non-RT waits; "0x0000002A" (digits hex digits).
  static std::int64_t now_ms() noexcept;
  static std::string hex(std::uint32_t v, int digits);

  // The shared part of describe(): transport kinds; the profile adds its own.
  std::string describe_transport(const DeviceFault& f) const;
  CanFaultKind fault_kind() const noexcept { return kind_; }

  const CanSettings settings_;
  const double period_s_;
  CanCounters counters_;
  std::optional<CanSocket> socket_;
  std::vector<std::string> notices_;  // configure's (notices())

 private:
  void on_bus_event(const BusEvent& e) noexcept;

  Opener open_;
  std::uint32_t heartbeat_limit_ticks_;
  std::uint32_t ticks_since_heartbeat_ = 0;
  int tx_full_streak_ = 0;
  bool tx_full_this_tick_ = false;
  IoStatus pending_status_ = IoStatus::kOk;
  CanFaultKind kind_ = CanFaultKind::kNone;
  std::array<WireFrame, 6> emergency_{};
  std::size_t emergency_count_ = 0;
  std::atomic<int> emergency_fd_{-1};
};

}  // namespace hapticd::drivers::can
