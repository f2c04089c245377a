// The simulated encoder (device.sim): floor quantisation to counts_per_unit with optional
// Gaussian count noise (seeded, so a run repeats), or the exact position when counts_per_unit
// is 0 (ideal). One per simulated device: SimAxis's one axis, Mechanism's joints in turn.
#pragma once

#include <cstdint>
#include <random>

#include "config/config.h"

namespace hapticd::sim {

class Encoder {
 public:
  // Not RT-safe. Throws std::invalid_argument when counts_per_unit or noise_counts is
  // negative or not finite.
  explicit Encoder(const config::SimDeviceConfig& sim);

  // Back to the first reading: the noise re-seeded.
  void reset() noexcept;
  // RT-safe. The reading of `position` in counts (floor of position * counts_per_unit plus
  // noise) and in units (counts / counts_per_unit; `position` itself when ideal).
  std::int64_t counts(double position) noexcept;
  double reading(double position) noexcept;
  double counts_per_unit() const noexcept { return counts_per_unit_; }

 private:
  double noisy_counts(double position) noexcept;

  double counts_per_unit_;
  double noise_counts_;
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
};

}  // namespace hapticd::sim
