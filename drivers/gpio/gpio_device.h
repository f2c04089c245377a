// The GPIO Device (docs/drivers/gpio.md): for each joint, a quadrature encoder on two GPIO lines
// decoded x4 from the kernel's timestamped edges, an optional index line that re-zeroes the
// count, an optional motor-driver fault line, and a motor driver taking a sysfs PWM duty plus a
// direction line: duty = |u| / max_force * period. A fault of any joint faults the device (the
// base class then writes zero to every joint), its cause naming the joint. The transport
// (kernel or loopback peer) is behind gpio_transport.h, so this code is the same for both.
//
// A sample's time is the last A/B edge's kernel timestamp when the tick brought one that
// happened since the previous read; when it brought none the shaft has not moved and the
// position is still current: the time is then the moment up to which the edge stream is
// complete (the read time), and the status bit kStatusNoEdge says so. (The first read after
// configure, whose edges may be a backlog from long before, also takes the read time.)
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include "drivers/device.h"
#include "drivers/gpio/gpio_settings.h"
#include "drivers/gpio/gpio_transport.h"
#include "drivers/gpio/quadrature_decoder.h"

namespace hapticd::drivers::gpio {

// PositionSample::status bits.
enum GpioStatus : std::uint32_t {
  kStatusNoEdge = 1u << 0,       // no A/B edge this tick: time_ns is the read time
  kStatusIndex = 1u << 1,        // the index re-zeroed the count this tick
  kStatusMissedEdges = 1u << 2,  // edges have been missed (within missed_edge_fault)
  kStatusFaultLine = 1u << 3,    // the motor driver's fault line is active
};

// Fault codes: the kind in the top byte, the joint in the next two bits, a detail (errno, count,
// rate) in the 22 below (a device of one joint's codes are what they were: joint 0).
enum class FaultKind : std::uint8_t {
  kReadError = 1,    // reading edge events failed (detail: errno)
  kWriteError = 2,   // writing the PWM or the direction line failed (detail: errno)
  kFaultLine = 3,    // the motor driver's fault line went active
  kMissedEdges = 4,  // more missed edges than missed_edge_fault (detail: how many)
  kEdgeRate = 5,     // edges faster than max_edge_rate (detail: the rate seen, edges/s)
};
std::uint32_t fault_code(FaultKind kind, std::uint64_t detail, std::size_t joint = 0) noexcept;

class GpioDevice final : public Device {
 public:
  static constexpr std::size_t kEdgeBuffer = 256;  // edges one tick can take in

  // max_force[j]: joint j's force at 100 % duty, for each of settings.joints.
  GpioDevice(const GpioSettings& settings, std::span<const double> max_force,
             std::unique_ptr<GpioTransport> transport, int declared_delay);

  std::string_view driver_name() const noexcept override { return "gpio"; }
  // Any thread: missed edges the tolerance absorbed, for the summary and `hapticctl status`.
  std::span<const base::Counter> counters() const noexcept override { return counters_; }
  void emergency_stop() noexcept override { transport_->emergency_stop(); }

  // Any thread, for tests and the summary (plain reads of RT-owned counters: approximate
  // while the loop runs).
  const QuadratureDecoder& decoder(std::size_t joint = 0) const noexcept {
    return joints_[joint].decoder;
  }
  std::uint64_t lost_edges(std::size_t joint = 0) const noexcept {
    return joints_[joint].decoder.lost();
  }

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
  // One joint's decoding and output state; fixed in number after construction.
  struct Joint {
    explicit Joint(const GpioSettings& s, std::size_t i);
    void restart(std::uint8_t levels) noexcept;  // the missed-edge ring emptied

    QuadratureDecoder decoder;
    bool direction_level = false;
    bool fault_line = false;
    // When each of the last missed_edge_fault + 1 missed edges was seen (a ring, preallocated).
    std::vector<std::int64_t> missed_times;
    std::size_t missed_next = 0;
    std::uint64_t missed_seen = 0;  // decoder.missed_edges() at the last read
    double max_force = 1.0;
  };

  bool logical(const Edge& e) const noexcept;
  std::uint8_t logical_levels(std::uint8_t raw) const noexcept;
  OutputState output(std::size_t joint, std::uint64_t duty_ns) const noexcept;
  IoStatus check_faults(std::size_t joint) noexcept;
  void note_missed(Joint& j, std::int64_t now_ns) noexcept;
  void sample(std::size_t joint, const EdgeRead& r, std::uint64_t ab_before,
              std::uint64_t hits_before, PositionSample& out) const noexcept;
  std::string who(std::size_t joint) const;

  GpioSettings s_;
  std::unique_ptr<GpioTransport> transport_;
  int declared_delay_;
  std::vector<Joint> joints_;
  std::array<Edge, kEdgeBuffer> edges_{};
  std::int64_t previous_complete_ns_ = 0;  // the last read's EdgeRead::complete_until_ns
  // The decoders' missed edges, every joint's together, published for other threads
  // (Device::counters).
  std::array<base::Counter, 1> counters_{{
      {"missed_edges", base::CounterKind::kAnomaly,
       "encoder edges missed within device.gpio.missed_edge_fault's tolerance: the count may "
       "be off by them (re-home on the index)"},
  }};
};

}  // namespace hapticd::drivers::gpio
