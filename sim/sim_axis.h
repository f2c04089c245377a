// The simulated device as every simulator of it sees it: the exact plant (sim/plant.h), an
// encoder with floor quantisation and optional Gaussian count noise, and the motor force held
// by a ZOH since the last command (zero while the amplifier is off). The in-process sim
// driver and every loopback peer (a HID firmware, a CiA 402 drive, an encoder on GPIO lines)
// wrap one of these, so they all simulate the same device from the same configuration.
#pragma once

#include <cstdint>
#include <vector>

#include "config/config.h"
#include "sim/encoder.h"
#include "sim/plant.h"

namespace hapticd::sim {

class SimAxis {
 public:
  // Not RT-safe. Throws std::invalid_argument on a bad configuration (see Plant, plus the
  // encoder's numbers). replay_positions: the imposed positions of OperatorSpec::Kind::kReplay.
  SimAxis(const config::DeviceConfig& config, double sample_period_s,
          std::vector<double> replay_positions = {});

  // Not RT-safe. Back to t = 0: initial state, noise re-seeded, amplifier off, force zero.
  void reset() noexcept;

  // RT-safe: advances exactly one sample period with the held force (zero while off), reversed
  // by a motor wired the other way round (device.sim.force_reversed).
  void step() noexcept { plant_.step(held_force()); }
  // RT-safe. The force held from the next step on, unclamped (saturation is the controller's).
  void hold_force(double force) noexcept { force_ = force; }
  // RT-safe. The amplifier; switching it either way drops the held force to zero.
  void set_output(bool on) noexcept {
    output_on_ = on;
    force_ = 0.0;
  }

  // RT-safe. The encoder at the current instant, in counts (floor of x * counts_per_unit plus
  // noise) and in axis units; an ideal encoder (counts_per_unit 0) reports x exactly.
  std::int64_t encoder_counts() noexcept { return encoder_.counts(plant_.position()); }
  double encoder_position() noexcept { return encoder_.reading(plant_.position()); }
  double counts_per_unit() const noexcept { return encoder_.counts_per_unit(); }

  // The force the plant feels: the one held, reversed with device.sim.force_reversed.
  double held_force() const noexcept { return output_on_ ? motor_sign_ * force_ : 0.0; }
  bool output_on() const noexcept { return output_on_; }
  const Plant& plant() const noexcept { return plant_; }
  double sample_period_s() const noexcept { return plant_.sample_period_s(); }

 private:
  Plant plant_;
  Encoder encoder_;
  double force_ = 0.0;
  bool output_on_ = false;
  double motor_sign_ = 1.0;  // -1: device.sim.force_reversed
};

}  // namespace hapticd::sim
