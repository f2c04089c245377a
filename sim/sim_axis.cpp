#include "sim/sim_axis.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace hapticd::sim {
namespace {

const config::DeviceConfig& validated(const config::DeviceConfig& c) {
  if (!std::isfinite(c.sim.counts_per_unit) || c.sim.counts_per_unit < 0.0) {
    throw std::invalid_argument("sim device: counts_per_unit must be finite and >= 0 (0 = ideal)");
  }
  if (!std::isfinite(c.sim.noise_counts) || c.sim.noise_counts < 0.0) {
    throw std::invalid_argument("sim device: noise_counts must be finite and >= 0");
  }
  return c;
}

}  // namespace

SimAxis::SimAxis(const config::DeviceConfig& config, double sample_period_s,
                 std::vector<double> replay_positions)
    : plant_(validated(config).mass[0], config.damping[0], config.sim.op, sample_period_s,
             config.sim.initial_position, config.sim.initial_velocity, std::move(replay_positions)),
      counts_per_unit_(config.sim.counts_per_unit),
      noise_counts_(config.sim.noise_counts),
      seed_(config.sim.seed),
      rng_(config.sim.seed),
      motor_sign_(config.sim.force_reversed ? -1.0 : 1.0) {}

void SimAxis::reset() noexcept {
  plant_.reset();
  rng_.seed(seed_);
  noise_.reset();  // drop a cached second normal so the sequence restarts identically
  force_ = 0.0;
  output_on_ = false;
}

double SimAxis::noisy_counts() noexcept {
  double counts = plant_.position() * counts_per_unit_;
  if (seed_ != 0 && noise_counts_ > 0.0) counts += noise_counts_ * noise_(rng_);
  return std::floor(counts);
}

std::int64_t SimAxis::encoder_counts() noexcept {
  return static_cast<std::int64_t>(noisy_counts());
}

double SimAxis::encoder_position() noexcept {
  if (counts_per_unit_ == 0.0) return plant_.position();  // ideal encoder
  return noisy_counts() / counts_per_unit_;
}

}  // namespace hapticd::sim
