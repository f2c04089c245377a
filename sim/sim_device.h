// The simulated device behind the Device seam: the exact plant (sim/plant.h) plus an encoder
// with floor quantisation and optional Gaussian count noise. One read() per tick advances the
// simulation by exactly one sample period with the force last written (zero while output is
// disabled, like an amplifier that is off). In-process, so no transport delay.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "drivers/device.h"
#include "drivers/transport_delay.h"
#include "sim/plant.h"

namespace hapticd::sim {

class SimDevice final : public hapticd::Device {
 public:
  // device_status bit set while output is enabled.
  static constexpr std::uint32_t kStatusOutputEnabled = 1u << 0;

  // Throws std::invalid_argument on a bad configuration (see Plant, plus encoder numbers).
  // replay_positions: the imposed positions for OperatorSpec::Kind::kReplay.
  SimDevice(const config::DeviceConfig& config, double sample_period_s,
            std::vector<double> replay_positions = {});

  // Not RT-safe. Back to the configured initial state at t = 0, noise generator re-seeded,
  // output disabled, command zero. Must be called before read()/write().
  void configure() override;
  // Not RT-safe. Output on; the stored command restarts from zero so no stale force appears.
  void enable_output() override;
  // Not RT-safe, never throws. Output off and command zero.
  void disable_output() noexcept override;

  // RT-safe: called every tick. The first call after configure() samples the initial state;
  // each later call first advances the plant one period with the last written force (zero if
  // output is disabled), then samples the encoder.
  IoStatus read(PositionSample& out) noexcept override;
  // RT-safe: called every tick. Stores the command for the next period, unclamped (saturation
  // is the controller's job). A non-finite force is refused with kError and zero is stored.
  IoStatus write(double force) noexcept override;

  // RT-safe: called every tick.
  int transport_delay_samples() const noexcept override {
    return declared_transport_delay(config::DriverKind::kSim);
  }
  std::string_view name() const noexcept override { return "sim"; }
  std::string describe_error() const override;

  double last_command() const noexcept override { return force_; }
  bool output_enabled() const noexcept override { return enabled_; }

  const Plant& plant() const noexcept { return plant_; }

 private:
  enum class Error : std::uint8_t { kNone, kNotConfigured, kNonFiniteForce };

  double encode(double x) noexcept;

  Plant plant_;
  double counts_per_unit_;
  double noise_counts_;
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  bool configured_ = false;
  bool first_read_ = true;
  bool enabled_ = false;
  double force_ = 0.0;
  Error error_ = Error::kNone;
};

}  // namespace hapticd::sim
