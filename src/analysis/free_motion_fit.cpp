#include "analysis/free_motion_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace hapticd::analysis {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The model's columns for one tau: the positions are cols * [x0, v0, 1/b, c/b].
struct Columns {
  MatrixXd a;  // one row per valid sample
  VectorXd y;
};

// Response x' to the input w of the model with b = 1 (x'_0 = v'_0 = 0), at every tick.
std::vector<double> response(const std::vector<double>& w, double tau, double period) {
  const double a = std::exp(-period / tau), gain_v = 1.0 - a;
  const double from_v = tau * (1.0 - a), from_u = period - tau * (1.0 - a);
  std::vector<double> x(w.size() + 1, 0.0);
  double v = 0.0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    x[k + 1] = x[k] + from_v * v + from_u * w[k];
    v = a * v + gain_v * w[k];
  }
  x.resize(w.size());
  return x;
}

struct Inputs {
  std::vector<double> force;     // acting over period k: u_{k-d}
  std::vector<double> friction;  // -sign(v_k) from the positions
};

Inputs inputs(const FreeMotionData& d, int delay) {
  const std::size_t n = d.force.size();
  Inputs in{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  for (std::size_t k = 0; k < n; ++k) {
    if (k >= static_cast<std::size_t>(delay)) in.force[k] = d.force[k - delay];
    const std::size_t lo = k == 0 ? 0 : k - 1, hi = std::min(k + 1, n - 1);
    const double dx = d.position[hi] - d.position[lo];
    in.friction[k] = dx > 0.0 ? -1.0 : dx < 0.0 ? 1.0 : 0.0;
  }
  return in;
}

Columns columns(const FreeMotionData& d, const Inputs& in, double tau, bool coulomb) {
  const std::vector<double> xu = response(in.force, tau, d.sample_period);
  const std::vector<double> xs = coulomb ? response(in.friction, tau, d.sample_period) : xu;
  const double a = std::exp(-d.sample_period / tau);
  std::size_t rows = 0;
  for (std::size_t k = 0; k < d.position.size(); ++k) rows += d.valid[k] ? 1 : 0;
  Columns c{MatrixXd(rows, coulomb ? 4 : 3), VectorXd(rows)};
  double ak = 1.0;  // a^k
  for (std::size_t k = 0, r = 0; k < d.position.size(); ++k, ak *= a) {
    if (!d.valid[k]) continue;
    c.a(r, 0) = 1.0;
    c.a(r, 1) = tau * (1.0 - ak);
    c.a(r, 2) = xu[k];
    if (coulomb) c.a(r, 3) = xs[k];
    c.y(r) = d.position[k];
    ++r;
  }
  return c;
}

struct Solved {
  double rss = std::numeric_limits<double>::infinity();
  VectorXd theta;
};

Solved solve(const FreeMotionData& d, const Inputs& in, double tau, bool coulomb) {
  const Columns c = columns(d, in, tau, coulomb);
  Solved s;
  s.theta = c.a.colPivHouseholderQr().solve(c.y);
  s.rss = (c.a * s.theta - c.y).squaredNorm();
  if (!std::isfinite(s.rss)) s.rss = std::numeric_limits<double>::infinity();
  return s;
}

// The tau with the least residual: a log grid, then golden section around the best point.
double best_tau(const FreeMotionData& d, const Inputs& in, bool coulomb) {
  const double span = static_cast<double>(d.force.size()) * d.sample_period;
  const double lo = std::log(d.sample_period / 4.0), hi = std::log(std::max(1e3, 100.0 * span));
  constexpr int kGrid = 80;
  const auto at = [&](double lt) { return solve(d, in, std::exp(lt), coulomb).rss; };
  int best = 0;
  double best_rss = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kGrid; ++i) {
    const double r = at(lo + (hi - lo) * i / kGrid);
    if (r < best_rss) best_rss = r, best = i;
  }
  if (best == kGrid) {
    throw std::invalid_argument(
        "the motion looks undamped over this excitation (time constant m/b beyond " +
        std::to_string(std::exp(hi)) + " s): excite lower frequencies or longer");
  }
  double a = lo + (hi - lo) * std::max(best - 1, 0) / kGrid;
  double b = lo + (hi - lo) * std::min(best + 1, kGrid) / kGrid;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double c = b - g * (b - a), e = a + g * (b - a);
  double fc = at(c), fe = at(e);
  for (int i = 0; i < 80 && b - a > 1e-12; ++i) {
    if (fc < fe) {
      b = e, e = c, fe = fc, c = b - g * (b - a), fc = at(c);
    } else {
      a = c, c = e, fc = fe, e = a + g * (b - a), fe = at(e);
    }
  }
  return std::exp((a + b) / 2.0);
}

struct ModelFit {
  double tau = 0.0;
  Solved s;
  MatrixXd cov;  // of [ln tau, x0, v0, 1/b, (c/b)]
  std::size_t n = 0;
};

ModelFit fit_model(const FreeMotionData& d, const Inputs& in, bool coulomb) {
  ModelFit f;
  f.tau = best_tau(d, in, coulomb);
  f.s = solve(d, in, f.tau, coulomb);
  const Columns c = columns(d, in, f.tau, coulomb);
  f.n = static_cast<std::size_t>(c.y.size());
  // The Jacobian of the predicted positions: the linear columns, and d/d(ln tau) numerically.
  const double h = 1e-5;
  const VectorXd up = columns(d, in, f.tau * std::exp(h), coulomb).a * f.s.theta;
  const VectorXd down = columns(d, in, f.tau * std::exp(-h), coulomb).a * f.s.theta;
  MatrixXd j(c.a.rows(), c.a.cols() + 1);
  j.col(0) = (up - down) / (2.0 * h);
  j.rightCols(c.a.cols()) = c.a;
  const auto p = static_cast<double>(j.cols());
  const double sigma2 = f.s.rss / std::max(1.0, static_cast<double>(f.n) - p);
  f.cov = sigma2 * (j.transpose() * j).completeOrthogonalDecomposition().pseudoInverse();
  return f;
}

FreeMotionFit to_physical(const ModelFit& f, bool coulomb) {
  constexpr double z = 1.959963984540054;  // two-sided 95 % of the normal distribution
  FreeMotionFit out;
  // A negative 1/b with tau > 0 is a negative mass and damping: the device moved against the
  // force, which is the same fit as a positive device driven by the force reversed.
  out.force_reversed = f.s.theta(2) < 0.0;
  const double sign = out.force_reversed ? -1.0 : 1.0;
  const double beta = sign * f.s.theta(2);
  const double b = 1.0 / beta, m = f.tau * b;
  if (!(beta > 0.0) || !std::isfinite(b) || !std::isfinite(m) || !(m > 0.0)) {
    throw std::invalid_argument(
        "the fit found no mass and damping: the data are not a free device moved by the "
        "force (is the device held, or at an end stop?)");
  }
  // Delta method on [ln tau, 1/b (, c/b)]; a reversed fit's covariances with 1/b change sign.
  const double var_lt = f.cov(0, 0), var_beta = f.cov(3, 3), cov_lt_beta = sign * f.cov(0, 3);
  if (!(beta > 4.0 * std::sqrt(var_beta))) {
    throw std::invalid_argument(
        "the force did not measurably move the device (is it held, or at an end stop?)");
  }
  out.damping = {b, z * std::sqrt(var_beta) / (beta * beta)};
  out.mass = {m, z * m *
                     std::sqrt(std::max(
                         0.0, var_lt + var_beta / (beta * beta) - 2.0 * cov_lt_beta / beta))};
  if (coulomb) {
    // Friction opposes the motion whichever way the force acts: c/b keeps its sign.
    const double gamma = f.s.theta(3);
    const double dg = 1.0 / beta, db = -sign * gamma / (beta * beta);
    const double var = dg * dg * f.cov(4, 4) + db * db * var_beta + 2.0 * dg * db * f.cov(3, 4);
    out.coulomb = {gamma / beta, z * std::sqrt(std::max(0.0, var))};
  }
  out.rms_residual = std::sqrt(f.s.rss / static_cast<double>(f.n));
  out.samples = f.n;
  return out;
}

void check(const FreeMotionData& d) {
  if (!(d.sample_period > 0.0) || !std::isfinite(d.sample_period)) {
    throw std::invalid_argument("the sample period must be finite and > 0");
  }
  if (d.force.size() != d.position.size() || d.valid.size() != d.position.size()) {
    throw std::invalid_argument("force, position and validity series differ in length");
  }
  const auto valid = static_cast<std::size_t>(std::count(d.valid.begin(), d.valid.end(), true));
  if (valid < 50) throw std::invalid_argument("fewer than 50 valid samples to fit");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t k = 0; k < d.position.size(); ++k) {
    if (d.valid[k]) lo = std::min(lo, d.position[k]), hi = std::max(hi, d.position[k]);
  }
  if (!(hi > lo)) {
    throw std::invalid_argument("the device did not move (is it held, or at an end stop?)");
  }
  if (std::none_of(d.force.begin(), d.force.end(), [](double u) { return u != 0.0; })) {
    throw std::invalid_argument("the force never moved the device: nothing to fit");
  }
  if (d.delay < 0) throw std::invalid_argument("the delay must be >= 0");
}

}  // namespace

FreeMotionFit fit_free_motion(const FreeMotionData& data) {
  check(data);
  // The delay the transport declares, or a neighbour when that fits better.
  int best_delay = data.delay;
  double best_rss = std::numeric_limits<double>::infinity();
  for (int delay = std::max(0, data.delay - 2); delay <= data.delay + 2; ++delay) {
    const Inputs in = inputs(data, delay);
    const double tau = best_tau(data, in, false);
    const double rss = solve(data, in, tau, false).rss;
    if (rss < best_rss) best_rss = rss, best_delay = delay;
  }
  const Inputs in = inputs(data, best_delay);
  FreeMotionFit plain = to_physical(fit_model(data, in, false), false);
  plain.delay = best_delay;
  // Friction is kept only when its estimate stands clear of zero (twice its 95 % interval),
  // is a force a device has (> 0) and matters (over 0.5 % of the largest force applied).
  FreeMotionFit with = plain;
  try {
    with = to_physical(fit_model(data, in, true), true);
    with.delay = best_delay;
  } catch (const std::invalid_argument&) {
    return plain;
  }
  double peak = 0.0;
  for (const double u : data.force) peak = std::max(peak, std::abs(u));
  if (with.coulomb.value > 2.0 * with.coulomb.ci95 && with.coulomb.value > 0.005 * peak &&
      with.rms_residual < plain.rms_residual) {
    with.coulomb_kept = true;
    return with;
  }
  return plain;
}

std::vector<double> free_motion_response(const std::vector<double>& force, double mass,
                                         double damping, double sample_period) {
  std::vector<double> x = response(force, mass / damping, sample_period);
  for (double& v : x) v /= damping;
  return x;
}

std::vector<double> multisine(double amplitude, double f_low, double f_high, double duration,
                              double sample_period, double fade, int components) {
  if (!(sample_period > 0.0) || !(duration > 0.0) || !std::isfinite(duration)) {
    throw std::invalid_argument("the duration and sample period must be finite and > 0");
  }
  if (!(f_low >= 1.0 / duration)) {
    throw std::invalid_argument(
        "the lowest frequency must be at least one cycle over the duration");
  }
  if (!(f_high > f_low) || !(f_high < 0.5 / sample_period)) {
    throw std::invalid_argument("the band must be non-empty and below the Nyquist frequency");
  }
  const auto n = static_cast<std::size_t>(std::llround(duration / sample_period));
  std::vector<double> harmonics;
  for (int i = 0; i < components; ++i) {
    const double f =
        f_low * std::pow(f_high / f_low, components > 1 ? double(i) / (components - 1) : 0.0);
    const double h = std::max(1.0, std::round(f * duration));
    if (harmonics.empty() || h > harmonics.back()) harmonics.push_back(h);
  }
  std::vector<double> u(n, 0.0);
  const double pi = std::numbers::pi;
  const auto count = static_cast<double>(harmonics.size());
  for (std::size_t i = 0; i < harmonics.size(); ++i) {
    const double phase = -pi * static_cast<double>(i) * static_cast<double>(i + 1) / count;
    const double w = 2.0 * pi * harmonics[i] / duration;
    for (std::size_t k = 0; k < n; ++k)
      u[k] += std::cos(w * static_cast<double>(k) * sample_period + phase);
  }
  double peak = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * sample_period, end = duration - t;
    const double edge = std::min(t, end);
    if (fade > 0.0 && edge < fade) u[k] *= 0.5 - 0.5 * std::cos(pi * edge / fade);
    peak = std::max(peak, std::abs(u[k]));
  }
  for (double& v : u) v *= amplitude / peak;
  return u;
}

}  // namespace hapticd::analysis
