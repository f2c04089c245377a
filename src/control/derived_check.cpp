#include "control/derived_check.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "analysis/wall_model.h"
#include "config/config_loader.h"
#include "control/control_law.h"

namespace hapticd::control {
namespace {

bool all_finite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

bool finite_tf(const analysis::TransferFunction& tf) {
  return all_finite(tf.num) && all_finite(tf.den);
}

// num/den normalised by den[0], as the controller and the analysis use it.
bool finite_normalised(const std::vector<double>& num, const std::vector<double>& den) {
  for (const std::vector<double>* p : {&num, &den})
    for (double x : *p)
      if (!std::isfinite(x / den.front())) return false;
  return true;
}

std::string seconds(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", t);
  return buf;
}

class Problems {
 public:
  explicit Problems(const config::Config& cfg) : cfg_(cfg) {}
  void add(const std::string& key, const std::string& what) {
    messages_.push_back(cfg_.locate(key) + ": " + key + ": " + what);
  }
  void throw_if_any() const {
    if (!messages_.empty()) throw config::ConfigError(messages_);
  }

 private:
  const config::Config& cfg_;
  std::vector<std::string> messages_;
};

void check_wall(const config::Config& cfg, Problems& p) {
  const double t = cfg.loop.sample_period_s();
  const analysis::TransferFunction e =
      analysis::environment_filter(wall_params(cfg, cfg.wall.stiffness));
  if (!finite_tf(e)) {
    const bool damping = !std::isfinite(2.0 * cfg.wall.damping / t);
    p.add(damping ? "wall.damping" : "wall.stiffness",
          std::string("makes the wall filter E(z) overflow (") + (damping ? "B/T" : "K + B/T") +
              " is not a finite number at T = " + seconds(t) + ")");
    return;
  }
  if (!cfg.wall.coupling.present) return;
  const config::CouplingConfig& c = cfg.wall.coupling;
  if (!finite_normalised(c.numerator, c.denominator)) {
    p.add("wall.coupling",
          "coefficients divided by denominator[0] overflow: C(z) is not a finite filter");
    return;
  }
  const double e0 = e.num.front() / e.den.front();
  const double c0 = c.numerator.front() / c.denominator.front();
  const double loop_gain = 1.0 + e0 * c0;
  const analysis::TransferFunction h = analysis::contact_map(e, coupling_filter(cfg));
  if (!std::isfinite(loop_gain) || !finite_tf(h) || !finite_normalised(h.num, h.den)) {
    p.add("wall.coupling",
          "the contact map E/(1 + E C) overflows with this wall (its coefficients are not "
          "finite numbers)");
  }
}

void check_models(const config::Config& cfg, Problems& p) {
  const auto& w = cfg.analysis;
  if (!finite_normalised(w.transparency_weight_numerator, w.transparency_weight_denominator)) {
    p.add("analysis.transparency_weight",
          "coefficients divided by denominator[0] overflow: W(z) is not a finite filter");
  }
  const analysis::TransferFunction g =
      analysis::device_operator_zoh(cfg.device.mass[0], cfg.device.damping[0], w.operator_stiffness,
                                    w.operator_damping, cfg.loop.sample_period_s());
  if (!finite_tf(g)) {
    p.add("analysis.operator",
          "the device pressed by this operator model (device.mass, device.damping, stiffness, "
          "damping) cannot be discretised at this rate: its ZOH model overflows");
  }
}

}  // namespace

void check_derived_quantities(const config::Config& cfg) {
  Problems p(cfg);
  const double t = cfg.loop.sample_period_s();
  if (!std::isfinite(t) || t <= 0.0) {
    p.add("loop.rate_hz", "the sample period 1/rate_hz is not a finite positive number");
    p.throw_if_any();
  }
  check_wall(cfg, p);
  check_models(cfg, p);
  p.throw_if_any();
}

}  // namespace hapticd::control
