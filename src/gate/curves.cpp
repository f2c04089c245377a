#include "gate/curves.h"

#include <cmath>
#include <numbers>

#include "analysis/polynomial.h"
#include "analysis/wall_model.h"
#include "control/control_law.h"

namespace hapticd::gate {

std::vector<ZwidthPoint> zwidth_curve(const config::Config& cfg, int device_delay_samples,
                                      int points) {
  const double t = cfg.loop.sample_period_s();
  const int delay = cfg.wall.delay_samples + device_delay_samples;
  const double available = (1.0 - cfg.safety.passivity_margin) * cfg.device.damping[0];
  const auto c = control::coupling_filter(cfg);
  std::vector<ZwidthPoint> out;
  for (int i = 0; i < points; ++i) {
    config::Config at = cfg;
    at.wall.damping = 2.0 * available * i / (points - 1);
    const auto limit = analysis::max_stiffness(
        [&](double k) {
          return analysis::contact_map(analysis::environment_filter(control::wall_params(at, k)),
                                       c);
        },
        t, delay, cfg.safety.operator_passivity_shortage, available);
    out.push_back({at.wall.damping, limit});
    if (limit.kind == analysis::StiffnessLimit::Kind::kNone) break;  // and for every larger B
  }
  return out;
}

analysis::TransferFunction oscillation_loop(const config::Config& cfg,
                                            const analysis::TransferFunction& environment,
                                            const std::optional<analysis::TransferFunction>& c,
                                            int delay_samples) {
  // The loop seen by xi(.): E (z^-d G + C), which is docs/math.md's E z^-d G without coupling.
  const analysis::TransferFunction g = analysis::device_operator_zoh(
      cfg.device.mass[0], cfg.device.damping[0], cfg.analysis.operator_stiffness,
      cfg.analysis.operator_damping, cfg.loop.sample_period_s());
  analysis::TransferFunction path = analysis::tf_delay(g, delay_samples);
  if (c) path = analysis::tf_sum(path, *c);
  return analysis::tf_product(environment, path);
}

std::vector<NyquistPoint> nyquist_curve(const config::Config& cfg, int device_delay_samples,
                                        std::string& note, int points) {
  std::vector<NyquistPoint> out;
  const auto c = control::coupling_filter(cfg);
  if (c && analysis::poly_has_root_at(c->den, 1.0)) {
    note = kCouplingPoleNote;
    return out;
  }
  const analysis::TransferFunction l = oscillation_loop(
      cfg, analysis::environment_filter(control::wall_params(cfg, cfg.wall.stiffness)), c,
      cfg.wall.delay_samples + device_delay_samples);
  // A quarter of the points log-spaced up to 0.01 pi (where a device's resonance usually is at
  // kHz rates), the rest evenly to pi.
  const int slow = points / 4;
  const double pi = std::numbers::pi;
  for (int i = 0; i < slow; ++i) {
    const double theta = 1e-4 * pi * std::pow(100.0, double(i) / slow);
    out.push_back({theta, analysis::frequency_response(l, theta)});
  }
  for (int i = 0; i < points - slow; ++i) {
    const double theta = 0.01 * pi + (0.99 * pi) * (i + 1) / (points - slow);
    out.push_back({theta, analysis::frequency_response(l, theta)});
  }
  return out;
}

}  // namespace hapticd::gate
