#include "sim/sim_axis.h"

#include <utility>

namespace hapticd::sim {

SimAxis::SimAxis(const config::DeviceConfig& config, double sample_period_s,
                 std::vector<double> replay_positions)
    : plant_(config.mass[0], config.damping[0], config.sim.op, sample_period_s,
             config.sim.initial_position, config.sim.initial_velocity, std::move(replay_positions)),
      encoder_(config.sim),
      motor_sign_(config.sim.force_reversed ? -1.0 : 1.0) {}

void SimAxis::reset() noexcept {
  plant_.reset();
  encoder_.reset();
  force_ = 0.0;
  output_on_ = false;
}

}  // namespace hapticd::sim
