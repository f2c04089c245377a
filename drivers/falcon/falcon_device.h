// The Falcon driver's Device (docs/drivers/falcon.md). configure opens the transport, loads
// Novint's firmware unless it already runs (firmware_loader.h), then waits, LED red, for the
// person to home the grip (pulled all the way out, pushed back in) until the firmware reports
// all three encoders homed; only then are positions read (before homing the encoders are
// relative: libnifalcon warns that torques from them "can lead to violence"). Each tick read()
// drains the IN stream and keeps the newest well-formed packet, each arm's angle from its count;
// write() sends one packet: each joint's torque in counts, the homing bit (the firmware keeps
// the device homed only while every packet carries it) and the LED (blue: homed, output off;
// green: output on; red: not homed or faulted). While output is off, read() sends the zero
// packet the firmware answers. No packet for liveness_ms is a transport fault, homing lost a
// device fault; malformed packets and skipped bytes are counted, never logged from the tick.
#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <memory>

#include "drivers/device.h"
#include "drivers/falcon/falcon_settings.h"
#include "drivers/falcon/falcon_transport.h"
#include "drivers/falcon/firmware_loader.h"

namespace hapticd::drivers::falcon {

class FalconDevice final : public Device {
 public:
  // Not RT-safe. `open` opens the transport (called by configure, again after a close).
  FalconDevice(std::shared_ptr<const FalconSettings> settings,
               std::function<std::unique_ptr<FalconTransport>()> open, double sample_period_s,
               const LoaderTiming& timing = {});
  ~FalconDevice() override;

  std::string_view driver_name() const noexcept override { return "falcon"; }
  std::vector<std::string> notices() const override { return notices_; }
  std::span<const base::Counter> counters() const noexcept override { return c_; }
  void emergency_stop() noexcept override;

 protected:
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_clear_fault() override;
  void on_close() noexcept override;
  IoStatus on_read(std::span<PositionSample> samples) noexcept override;
  IoStatus on_write(std::span<const double> forces) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  enum CounterIndex : std::size_t {
    kPackets,
    kSuperseded,
    kMalformed,
    kSkipped,
    kOverflow,
    kSent,
    kOutFull,
    kCounterCount
  };
  // Why a fault latched (DeviceFault::code): an errno, or one of these.
  static constexpr std::uint32_t kSilent = 0x10000;      // no packet for liveness_ms
  static constexpr std::uint32_t kHomingLost = 0x10002;  // the firmware dropped a homed bit

  void load();
  void home();
  // RT-safe. One packet out with `motor` counts and `leds`; false when the transport failed.
  bool send(const std::array<std::int16_t, 3>& motor, std::uint8_t leds) noexcept;
  void send_zero(std::uint8_t leds) noexcept;
  // RT-safe. Drains the transport; the count of good packets, -1 when it failed.
  int drain() noexcept;
  void publish_stream() noexcept;

  std::shared_ptr<const FalconSettings> settings_;
  std::function<std::unique_ptr<FalconTransport>()> open_;
  double period_s_;
  LoaderTiming timing_;
  std::unique_ptr<FalconTransport> transport_;
  std::atomic<FalconTransport*> emergency_{nullptr};  // what a crash handler may write to
  PacketStream stream_;
  State newest_;
  std::int64_t asked_ns_ = 0;  // the first packet sent since the last answer; 0: none
  std::int64_t liveness_ns_;
  std::uint32_t homing_code_ = 0;  // the homed bits when homing was lost
  std::vector<std::string> notices_;
  using K = base::CounterKind;
  std::array<base::Counter, kCounterCount> c_{{
      {"packets", K::kCount, "state packets read"},
      {"superseded", K::kCount, "packets replaced by a newer one in the same tick"},
      {"malformed", K::kAnomaly, "framed packets with a byte out of its range (not read)"},
      {"skipped_bytes", K::kAnomaly, "input bytes in no packet (a byte lost or added)"},
      {"overflow_bytes", K::kAnomaly, "input bytes dropped: more arrived than a tick holds"},
      {"packets_sent", K::kCount, "command packets the transport took"},
      {"out_full", K::kAnomaly,
       "ticks whose packet replaced one not yet sent (or, on the loopback, was not taken)"},
  }};
};

}  // namespace hapticd::drivers::falcon
