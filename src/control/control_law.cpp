#include "control/control_law.h"

#include <limits>
#include <stdexcept>
#include <string>

namespace hapticd::control {
namespace {

FilterCoefficients normalise(const std::vector<double>& num, const std::vector<double>& den,
                             const char* what) {
  if (num.empty() || den.empty() || den[0] == 0.0) {
    throw std::invalid_argument(std::string(what) +
                                ": needs a numerator and a denominator with den[0] != 0");
  }
  if (num.size() > kMaxTaps || den.size() > kMaxTaps) {
    throw std::invalid_argument(std::string(what) + ": at most " + std::to_string(kMaxTaps) +
                                " coefficients per polynomial");
  }
  FilterCoefficients f;
  const double inv = 1.0 / den[0];
  for (std::size_t i = 0; i < num.size(); ++i) f.num[i] = num[i] * inv;
  for (std::size_t i = 0; i < den.size(); ++i) f.den[i] = den[i] * inv;
  f.num_taps = num.size();
  f.den_taps = den.size();
  return f;
}

}  // namespace

analysis::WallParams wall_params(const config::Config& cfg, double stiffness) {
  return {stiffness, cfg.wall.damping, cfg.loop.sample_period_s(),
          cfg.wall.discretization == config::Discretization::kTustin
              ? analysis::WallDiscretization::kTustin
              : analysis::WallDiscretization::kBackward};
}

std::optional<analysis::TransferFunction> coupling_filter(const config::Config& cfg) {
  if (!cfg.wall.coupling.present) return std::nullopt;
  return analysis::TransferFunction{cfg.wall.coupling.numerator, cfg.wall.coupling.denominator};
}

double runaway_penetration(const config::Config& cfg) {
  if (cfg.safety.max_penetration > 0.0) return cfg.safety.max_penetration;
  if (cfg.wall.stiffness > 0.0) {
    return config::kRunawayMargin * cfg.device.max_force[0] / cfg.wall.stiffness;
  }
  return std::numeric_limits<double>::infinity();
}

ControlLaw make_control_law(const config::Config& cfg) {
  ControlLaw law;
  const double t = cfg.loop.sample_period_s();
  law.wall_position = cfg.wall.position;
  law.normal = static_cast<double>(cfg.wall.normal);
  const analysis::TransferFunction e =
      analysis::environment_filter(wall_params(cfg, cfg.wall.stiffness));
  law.environment = normalise(e.num, e.den, "wall");
  law.has_coupling = cfg.wall.coupling.present;
  if (law.has_coupling) {
    law.coupling =
        normalise(cfg.wall.coupling.numerator, cfg.wall.coupling.denominator, "wall.coupling");
  }
  law.delay_samples = cfg.wall.delay_samples;
  law.no_pull = cfg.wall.no_pull;
  law.max_force = cfg.device.max_force[0];
  law.runaway_penetration = runaway_penetration(cfg);
  law.sample_period = t;
  law.inv_sample_period = 1.0 / t;
  law.e0 = law.environment.num[0];
  law.c0 = law.has_coupling ? law.coupling.num[0] : 0.0;
  if (law.e0 < 0.0 || law.c0 < 0.0) {
    // docs/math.md: the contact algebraic loop has a unique solution only for e0, c0 >= 0.
    throw std::invalid_argument("wall: direct feed-through of E and C must be >= 0");
  }
  law.inv_one_plus_e0c0 = 1.0 / (1.0 + law.e0 * law.c0);
  return law;
}

}  // namespace hapticd::control
