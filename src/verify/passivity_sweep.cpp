#include "verify/passivity_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "analysis/passivity.h"
#include "analysis/wall_model.h"
#include "control/controller.h"
#include "loop/servo_loop.h"
#include "sim/sim_device.h"
#include "verify/frequency_sweep.h"

namespace hapticd::verify {
namespace {

constexpr double kPi = std::numbers::pi;

// The loop that will be measured: the configured wall and delays, a sim device with an ideal
// encoder, and none of the nonlinearities the theorem leaves out (no_pull, saturation).
config::Config measurement_config(const config::Config& base, int total_delay) {
  config::Config c = base;
  c.loop.clock = config::ClockMode::kFreerun;
  c.device.driver = "sim";
  c.device.settings = nullptr;
  c.device.max_force = std::numeric_limits<double>::max();
  c.device.sim.counts_per_unit = 0.0;
  c.device.sim.noise_counts = 0.0;
  c.device.sim.op.kind = config::OperatorSpec::Kind::kMotion;
  c.wall.no_pull = false;
  c.wall.delay_samples = total_delay;
  return c;
}

class Sweep final : public FrequencySweep {
 public:
  Sweep(const config::Config& base, int total_delay, double amplitude, bool nyquist_pole,
        double slowest_pole)
      : FrequencySweep(base.loop.sample_period_s(), nyquist_pole),
        cfg_(measurement_config(base, total_delay)),
        amplitude_(amplitude) {
    warmup_ = warmup_ticks(total_delay, slowest_pole);
  }

 private:
  // The zero of the cycle-averaged operator power at theta.
  double measure(double theta, std::int64_t period, std::int64_t window) override {
    const double b1 = cfg_.device.damping[0];
    const double b2 = 2.0 * b1;
    const auto [p1, p2] = powers(theta, period, window, b1, b2);
    // P(b) = P0 + b D is affine in b: its zero is where the device stops delivering energy.
    return b1 - p1 * (b2 - b1) / (p2 - p1);
  }

 private:
  // The cycle-averaged operator power over `window` ticks after the warm-up, at damping b1
  // and at b2. The motion is imposed and the encoder ideal, so the controller's state after
  // the warm-up does not depend on b: one warm-up, whose length is rounded up to whole
  // periods, serves both. Each window then runs on a fresh device whose motion starts where
  // the warm-up's ended (the same phase: x at a crest, where the forward and backward
  // velocities have the same size, so the device's kinetic energy is accounted as in one
  // unbroken run), with a copy of the warmed-up controller.
  std::pair<double, double> powers(double theta, std::int64_t period, std::int64_t window,
                                   double b1, double b2) {
    config::Config c = cfg_;
    const double t = c.loop.sample_period_s();
    // Penetration 2A + A cos(theta k): in contact throughout, so the wall is linear.
    c.device.sim.op.motion = {c.wall.position + c.wall.normal * 2.0 * amplitude_,
                              c.wall.normal * amplitude_, theta / (2.0 * kPi * t), 0.0};
    const std::int64_t warm = (warmup_ + period - 1) / period * period;
    control::ControlLaw law = control::make_control_law(c);
    law.require_outside_start = false;  // the motion starts in contact, where it stays
    law.linear_contact = true;          // the loop of the bound: linear, the contact never opens
    control::Controller warmed(law);
    operator_work(c, warmed, warm);
    const auto power = [&](double damping) {
      c.device.damping = damping;
      control::Controller controller = warmed;
      // window + 1 reads: the device steps between reads, so `window` periods of work.
      return operator_work(c, controller, window + 1) / (static_cast<double>(window) * t);
    };
    const double p1 = power(b1);
    const double p2 = power(b2);
    ticks_ += static_cast<std::uint64_t>(warm + 2 * (window + 1));
    // The premise of the measurement, kept as a check: with linear_contact every tick the
    // controller ran is in contact, so a tick out of it is one the loop did not control.
    if (!in_contact_) {
      throw std::runtime_error(
          "verify: the measurement loop was out of contact on some ticks, so the loop measured "
          "was not the linear one the bound is about");
    }
    return {p1, p2};
  }

  // Work the operator does on a fresh sim device in `ticks` ticks of the whole loop, with
  // `controller` (its state carries on from where it was).
  double operator_work(const config::Config& c, control::Controller& controller,
                       std::int64_t ticks) {
    const double t = c.loop.sample_period_s();
    sim::SimDevice device(c.device, t);
    loop::LoopOptions lo;
    lo.sample.realtime = false;
    lo.sample.period_ns = std::llround(t * 1e9);
    lo.sample.max_speed = std::numeric_limits<double>::infinity();
    lo.max_ticks = static_cast<std::uint64_t>(ticks);
    device.configure();
    device.enable();
    const std::atomic<bool> stop{false};
    loop::ServoLoop loop(device, controller, nullptr, lo);
    check(loop.run(stop));
    return device.axis().plant().operator_work_j();
  }

  void check(const loop::LoopResult& r) {
    if (r.fault.cause != loop::FaultCause::kNone) {
      throw std::runtime_error("verify: the measurement loop faulted: " + loop::describe(r.fault));
    }
    in_contact_ = in_contact_ && r.count(loop::kCounterContactTicks) == r.ticks;
  }

  config::Config cfg_;
  double amplitude_;
  std::int64_t warmup_ = 0;
  bool in_contact_ = true;
};

}  // namespace

VerifyResult verify_passivity(const config::Config& cfg, int device_delay_samples) {
  VerifyResult r;
  const double t = cfg.loop.sample_period_s();
  r.delay_samples = cfg.wall.delay_samples + device_delay_samples;
  const analysis::TransferFunction e =
      analysis::environment_filter(control::wall_params(cfg, cfg.wall.stiffness));
  const std::optional<analysis::TransferFunction> c = control::coupling_filter(cfg);
  const analysis::PassivityBound pb =
      analysis::passivity_bound(analysis::contact_map(e, c), t, r.delay_samples, 0.0);
  if (!std::isfinite(pb.required_damping)) {
    throw std::invalid_argument("verify: the passivity bound is infinite (" + pb.note +
                                "); nothing to measure");
  }
  r.analytic_required_damping = pb.required_damping;
  r.analytic_worst_frequency_hz = pb.worst_frequency_hz;

  // The amplitude only scales the energy; 1 mm keeps the numbers in a familiar range.
  r.amplitude = 1e-3;
  const bool tustin = cfg.wall.discretization == config::Discretization::kTustin;
  Sweep sweep(cfg, r.delay_samples, r.amplitude, tustin,
              analysis::spectral_radius(analysis::contact_map(e, c)));
  const double best = worst_damping(sweep, tustin);

  r.sweep = sweep.points();
  r.measured_required_damping = best;
  r.worst_frequency_hz = worst_frequency_hz(r.sweep, best);
  const double scale = std::max(std::abs(r.analytic_required_damping), 1e-12);
  r.relative_error = std::abs(r.measured_required_damping - r.analytic_required_damping) / scale;
  r.agrees = r.relative_error <= kVerifyTolerance;
  r.ticks = sweep.ticks();
  return r;
}

}  // namespace hapticd::verify
