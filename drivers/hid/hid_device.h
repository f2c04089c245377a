// The HID driver's Device: the lifecycle over a HidTransport (hidapi or the loopback
// socketpair) and a HidProfile (report or pid). Each tick it drains every pending input report
// and keeps the newest sample; a report's status bits under the fault mask are a device
// fault; a transport error, a device that is gone, or an output queue full for
// limits.out_queue_full_fault ticks in a row is a transport fault. Malformed reports (too
// short, an unknown id, too long) are counted, readable off the RT thread and logged when
// output is disabled, never a crash and never logged from the tick.
#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <memory>

#include "drivers/device.h"
#include "drivers/hid/hid_profile.h"
#include "drivers/hid/hid_settings.h"
#include "drivers/hid/hid_transport.h"

namespace hapticd::drivers::hid {

// A snapshot of the driver's counters (since configure).
struct HidCounters {
  std::uint64_t input_reports = 0;   // samples received
  std::uint64_t superseded = 0;      // samples drained in the same tick as a newer one
  std::uint64_t state_reports = 0;   // status-only reports (PID State)
  std::uint64_t unknown_id = 0;      // reports of an id the profile does not use
  std::uint64_t too_short = 0;       // our id, shorter than its layout
  std::uint64_t too_long = 0;        // longer than any report can be
  std::uint64_t output_reports = 0;  // handed to the transport
  std::uint64_t out_queue_full = 0;  // ticks whose report was dropped: the queue was full
  std::uint64_t drain_limit = 0;     // ticks that stopped draining at the per-tick bound
  std::uint64_t held = 0;            // ticks without a report, position held (on change)
};

class HidDevice final : public Device {
 public:
  // Not RT-safe. `open` opens the transport (called by configure, again after a close).
  HidDevice(std::shared_ptr<const HidSettings> settings,
            std::function<std::unique_ptr<HidTransport>()> open, double sample_period_s);
  ~HidDevice() override;

  std::string_view driver_name() const noexcept override { return "hid"; }
  void emergency_stop() noexcept override;
  // Any thread.
  HidCounters hid_counts() const noexcept;
  std::span<const base::Counter> counters() const noexcept override { return c_; }

 protected:
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_close() noexcept override;
  IoStatus on_read(std::span<PositionSample> samples) noexcept override;
  IoStatus on_write(std::span<const double> forces) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  static constexpr int kMaxDrain = 256;  // reports per tick: a flooding device cannot stall it
  // The driver's counters (Device::counters), in this order.
  enum CounterIndex : std::size_t {
    kInputReports,
    kSuperseded,
    kStateReports,
    kUnknownId,
    kTooShort,
    kTooLong,
    kOutputReports,
    kOutQueueFull,
    kDrainLimit,
    kHeld,
    kCounterCount
  };
  struct Drained {
    std::uint32_t samples = 0;  // position reports (the newest is decoded_)
    std::uint32_t reports = 0;  // well-formed reports of any kind: the device is alive
    int error = 0;              // the transport failed (errno)
  };
  // RT-safe: called every tick. Every pending input report, decoded into decoded_.
  Drained drain() noexcept;
  // RT-safe: called every tick. Joint 0's sample (the others share its all but position).
  IoStatus read_joint0(PositionSample& out) noexcept;
  IoStatus hold(PositionSample& out, std::int64_t now) noexcept;
  void await_first_sample();
  void bump(CounterIndex i) noexcept { c_[i].add(); }
  // RT-safe: called every tick. A report the queue has no room for is lost (`written` false),
  // counted, and faults the loop after limits.out_queue_full_fault such ticks in a row.
  IoStatus send(std::span<const std::uint8_t> report, bool& written) noexcept;
  void queue_pending(std::span<const std::uint8_t> r) noexcept;
  void log_counters() const;
  void drain_stale() noexcept;

  std::shared_ptr<const HidSettings> settings_;
  std::function<std::unique_ptr<HidTransport>()> open_;
  double period_s_;
  std::int64_t liveness_ns_;
  std::int64_t last_report_ns_ = 0;  // when the last well-formed report arrived
  bool have_position_ = false;       // a sample since enable: a held position is valid
  std::unique_ptr<HidTransport> transport_;
  std::unique_ptr<HidProfile> profile_;
  std::atomic<HidTransport*> emergency_{nullptr};
  std::array<std::uint8_t, kMaxReportData + 2> rx_{};
  Decoded decoded_;
  bool active_ = false;  // output enabled: the fault mask applies
  int queue_full_streak_ = 0;
  // The profile's before_force() reports not yet sent, oldest first: one per effect at most
  // (a pid profile of two axes restarts its effects on consecutive ticks; a full queue must
  // not let the second's restart replace the first's).
  std::array<std::span<const std::uint8_t>, base::kMaxJoints> pending_{};
  std::size_t pending_count_ = 0;
  using K = base::CounterKind;
  std::array<base::Counter, kCounterCount> c_{{
      {"input_reports", K::kCount, "input reports with a sample"},
      {"superseded", K::kCount, "samples replaced by a newer one in the same tick"},
      {"state_reports", K::kCount, "status-only reports (PID State)"},
      {"unknown_id_reports", K::kAnomaly, "input reports of an id the profile does not use"},
      {"short_reports", K::kAnomaly, "input reports shorter than their layout"},
      {"long_reports", K::kAnomaly, "input reports longer than any report can be"},
      {"output_reports", K::kCount, "output reports handed to the transport"},
      {"out_queue_full", K::kAnomaly, "ticks whose output report was dropped: queue full"},
      {"drain_limit", K::kAnomaly, "ticks that stopped draining at the per-tick bound"},
      {"held_ticks", K::kCount,
       "ticks without a report, the position held (a device that reports on change)"},
  }};
  mutable HidCounters logged_;  // what log_counters() last reported: each event is logged once
};

}  // namespace hapticd::drivers::hid
