#include "sim/encoder.h"

#include <cmath>
#include <stdexcept>

namespace hapticd::sim {

Encoder::Encoder(const config::SimDeviceConfig& sim)
    : counts_per_unit_(sim.counts_per_unit),
      noise_counts_(sim.noise_counts),
      seed_(sim.seed),
      rng_(sim.seed) {
  if (!std::isfinite(counts_per_unit_) || counts_per_unit_ < 0.0) {
    throw std::invalid_argument("sim device: counts_per_unit must be finite and >= 0 (0 = ideal)");
  }
  if (!std::isfinite(noise_counts_) || noise_counts_ < 0.0) {
    throw std::invalid_argument("sim device: noise_counts must be finite and >= 0");
  }
}

void Encoder::reset() noexcept {
  rng_.seed(seed_);
  noise_.reset();  // drop a cached second normal so the sequence restarts identically
}

double Encoder::noisy_counts(double position) noexcept {
  double counts = position * counts_per_unit_;
  if (seed_ != 0 && noise_counts_ > 0.0) counts += noise_counts_ * noise_(rng_);
  return std::floor(counts);
}

std::int64_t Encoder::counts(double position) noexcept {
  return static_cast<std::int64_t>(noisy_counts(position));
}

double Encoder::reading(double position) noexcept {
  if (counts_per_unit_ == 0.0) return position;  // ideal encoder
  return noisy_counts(position) / counts_per_unit_;
}

}  // namespace hapticd::sim
