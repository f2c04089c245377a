#include "sim/sim_device.h"

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

SimDevice::SimDevice(const config::DeviceConfig& config, double sample_period_s,
                     std::vector<double> replay_positions)
    : plant_(validated(config).mass, config.damping, config.sim.op, sample_period_s,
             config.sim.initial_position, config.sim.initial_velocity, std::move(replay_positions)),
      counts_per_unit_(config.sim.counts_per_unit),
      noise_counts_(config.sim.noise_counts),
      seed_(config.sim.seed),
      rng_(config.sim.seed) {}

void SimDevice::configure() {
  plant_.reset();
  rng_.seed(seed_);
  noise_.reset();  // drop a cached second normal so the sequence restarts identically
  configured_ = true;
  first_read_ = true;
  enabled_ = false;
  force_ = 0.0;
  error_ = Error::kNone;
}

void SimDevice::enable_output() {
  if (!configured_) throw DeviceError("sim: enable_output() called before configure()");
  force_ = 0.0;
  enabled_ = true;
}

void SimDevice::disable_output() noexcept {
  force_ = 0.0;
  enabled_ = false;
}

IoStatus SimDevice::read(PositionSample& out) noexcept {
  if (!configured_) {
    error_ = Error::kNotConfigured;
    return IoStatus::kError;
  }
  if (first_read_) {
    first_read_ = false;
  } else {
    plant_.step(enabled_ ? force_ : 0.0);
  }
  out.position = encode(plant_.position());
  out.device_status = enabled_ ? kStatusOutputEnabled : 0u;
  return IoStatus::kOk;
}

IoStatus SimDevice::write(double force) noexcept {
  if (!configured_) {
    error_ = Error::kNotConfigured;
    return IoStatus::kError;
  }
  if (!std::isfinite(force)) {
    force_ = 0.0;
    error_ = Error::kNonFiniteForce;
    return IoStatus::kError;
  }
  force_ = force;
  return IoStatus::kOk;
}

double SimDevice::encode(double x) noexcept {
  if (counts_per_unit_ == 0.0) return x;  // ideal encoder
  double counts = x * counts_per_unit_;
  if (seed_ != 0 && noise_counts_ > 0.0) counts += noise_counts_ * noise_(rng_);
  return std::floor(counts) / counts_per_unit_;
}

std::string SimDevice::describe_error() const {
  switch (error_) {
    case Error::kNotConfigured:
      return "sim: read() or write() called before configure()";
    case Error::kNonFiniteForce:
      return "sim: write() got a non-finite force command (NaN or infinity); zero applied";
    case Error::kNone:
      break;
  }
  return "sim: no error";
}

}  // namespace hapticd::sim
