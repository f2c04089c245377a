#include "analysis/coupling_shaping.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "analysis/coupling.h"

namespace hapticd::analysis {
namespace {

constexpr double kPi = std::numbers::pi;
// Re P >= this many T/(2b) on the grid, so that Theorem 1's strict inequality survives between
// grid points (the exact check decides; a point is added where it does not) with the margin
// the cone complementarity stage's designs have (min Re P about 1e-5 on Example 1).
constexpr double kDsprMargin = 1e-2;
constexpr int kRefinements = 4;  // grid points added per candidate before giving it up

// Grid: logarithmic from 1e-4 rad (0.016 Hz at 1 kHz, less at slower rates), where the weights
// of interest live, and linear over the upper half, where Theorem 1 bites.
std::vector<double> initial_grid() {
  std::vector<double> th;
  constexpr int kLog = 100, kLin = 30;
  for (int i = 0; i < kLog; ++i) th.push_back(1e-4 * std::pow(kPi / 1e-4, i / (kLog - 1.0)));
  for (int i = 1; i < kLin; ++i) th.push_back(0.5 * kPi * (1.0 + i / double(kLin)));
  return th;
}

void put(LmiBlock& b, int var, int row, int col, double value) {
  if (value != 0.0) b.entries.push_back({var, row, col, value});
}

}  // namespace

CouplingShaper::CouplingShaper(const CouplingSpec& spec, const SdpSolver& solver,
                               const TransferFunction& passive)
    : spec_(spec),
      solver_(solver),
      passive_(passive),
      unit_(spec.sample_period / (2.0 * spec.device_damping)) {
  for (double th : initial_grid()) add_point(th);
}

void CouplingShaper::add_point(double theta) {
  theta = std::clamp(theta, 1e-6, kPi);
  const Complex w = std::polar(1.0, -theta), z = 1.0 / w;
  const double t = spec_.sample_period;
  Point p;
  p.theta = theta;
  p.e = frequency_response(spec_.environment, theta);
  p.x0 = 1.0 + p.e * unit_;
  p.g = p.e * t * unit_ / (1.0 - w);
  p.a = t * p.e * std::pow(w, spec_.delay_samples) / (1.0 - z);
  p.xhat = 1.0 + p.e * frequency_response(passive_, theta);
  p.we = std::abs(frequency_response(spec_.weight, theta)) * std::abs(p.e);
  grid_.push_back(p);
}

std::optional<CouplingShaper::Solution> CouplingShaper::solve(const Polynomial& den, double gamma) {
  const int n = spec_.order + 1, tvar = n;  // m_0..m_order, then t
  LmiBlock scalars;
  int row = 0;
  // sum_k coeff(k) m_k + constant >= 0 as one row of the diagonal block.
  const auto scalar_row = [&](const auto& coeff, double constant) {
    for (int k = 0; k < n; ++k) put(scalars, k, row, row, coeff(k));
    put(scalars, -1, row, row, constant);
    ++row;
  };
  SdpProblem prob;
  for (const Point& p : grid_) {
    const Complex w = std::polar(1.0, -p.theta);
    const Complex dw = poly_eval(den, w);
    std::vector<Complex> phi(static_cast<std::size_t>(n));  // w^k / D(w): P / (T/(2b))
    for (int k = 0; k < n; ++k) phi[static_cast<std::size_t>(k)] = std::pow(w, k) / dw;
    const auto at = [&](int k) { return phi[static_cast<std::size_t>(k)]; };
    scalar_row([&](int k) { return at(k).real(); }, -kDsprMargin);  // Theorem 1
    const double h2 = std::norm(p.xhat);  // the passivity bound, linearised at xhat
    const Complex u = std::conj(2.0 * p.xhat - p.a / spec_.allowed_damping);
    scalar_row([&](int k) { return (p.g * at(k) * u).real() / h2; }, (p.x0 * u).real() / h2 - 1.0);
    const double rho = std::sqrt(gamma) / p.we;
    if (!(rho < 1.0)) {  // |1/x - 1| <= 1 <= rho where Re x >= 1/2
      const double s = std::max(1.0, std::abs(p.xhat));
      scalar_row([&](int k) { return (p.g * at(k)).real() / s; }, (p.x0.real() - 0.5) / s);
      continue;
    }
    // |x - centre| <= radius (1 + t): [[r + Re v, Im v], [Im v, r - Re v]] >= 0, r = 1 + t.
    const double centre = 1.0 / (1.0 - rho * rho), radius = rho / (1.0 - rho * rho);
    const Complex v0 = (p.x0 - centre) / radius;
    LmiBlock disk{2, {}};
    put(disk, -1, 0, 0, 1.0 + v0.real());
    put(disk, -1, 1, 0, v0.imag());
    put(disk, -1, 1, 1, 1.0 - v0.real());
    put(disk, tvar, 0, 0, 1.0);
    put(disk, tvar, 1, 1, 1.0);
    for (int k = 0; k < n; ++k) {
      const Complex b = p.g * at(k) / radius;
      put(disk, k, 0, 0, b.real());
      put(disk, k, 1, 0, b.imag());
      put(disk, k, 1, 1, -b.real());
    }
    prob.blocks.push_back(std::move(disk));
  }
  put(scalars, tvar, row, row, 1.0);  // t >= -1 keeps the problem bounded
  put(scalars, -1, row, row, 1.0);
  scalars.size = ++row;
  prob.blocks.push_back(std::move(scalars));
  prob.variables = n + 1;
  prob.objective = Eigen::VectorXd::Unit(n + 1, tvar);
  const SdpSolution s = solver_.solve(prob);
  ++sdp_solves_;
  if (s.status != SdpSolution::Status::kSolved) return std::nullopt;
  return Solution{s.y(tvar), s.y.head(n)};
}

TransferFunction CouplingShaper::coupling_of(const Polynomial& den,
                                             const Eigen::VectorXd& m) const {
  // C = T/(2b) + T P / (1 - w), P = (T/(2b)) M / D: (T/(2b)) ((1 - w) D + T M) / ((1 - w) D).
  Polynomial mp(static_cast<std::size_t>(m.size()));
  for (Eigen::Index k = 0; k < m.size(); ++k) mp[static_cast<std::size_t>(k)] = m(k);
  const Polynomial d1 = poly_mul(den, {1.0, -1.0});
  const Polynomial num = poly_scale(poly_add(d1, poly_scale(mp, spec_.sample_period)), unit_);
  return {poly_trim(num), poly_trim(d1)};
}

std::optional<ShapedCoupling> CouplingShaper::verified(const Polynomial& den, double gamma) {
  for (int i = 0; i < kRefinements; ++i) {
    const std::optional<Solution> s = solve(den, gamma);
    if (!s || s->t > 0.0) return std::nullopt;
    const TransferFunction c = coupling_of(den, s->m);
    const CouplingVerdict v = evaluate_coupling(spec_, c);
    if (v.valid()) {
      // Where the exact peak lies off the grid, the next solves see it.
      if (v.gamma > gamma * 1.001) add_point(v.gamma_frequency_theta);
      return ShapedCoupling{c, v};
    }
    if (!v.theorem1 && v.dspr_worst_theta >= 0.0) {
      add_point(v.dspr_worst_theta);
    } else if (!v.passive && std::isfinite(v.required_damping)) {
      add_point(v.passivity_worst_theta);
    } else {
      return std::nullopt;  // unstable, or not admissible: no grid point mends that
    }
  }
  return std::nullopt;
}

double CouplingShaper::slack(const Polynomial& den, double gamma) {
  const std::optional<Solution> s = solve(den, gamma);
  return s ? s->t : std::numeric_limits<double>::infinity();
}

std::optional<ShapedCoupling> CouplingShaper::best(const Polynomial& den, double lo, double hi,
                                                   double tolerance) {
  std::optional<ShapedCoupling> out;
  const auto reaches = [&](double g) {
    std::optional<ShapedCoupling> c = verified(den, g);
    if (!c) return false;
    if (!out || c->verdict.gamma < out->verdict.gamma) out = std::move(c);
    return true;
  };
  // Below hi by a gap that doubles while it is reached (most moves gain little), then
  // bisection of the last gap missed.
  double reached = hi, missed = lo;
  for (double gap = tolerance; hi * (1.0 - gap) > lo; gap *= 2.0) {
    const double g = hi * (1.0 - gap);
    if (!reaches(g)) {
      missed = g;
      break;
    }
    reached = g;
  }
  while (reached > missed * (1.0 + tolerance)) {
    const double g = std::sqrt(missed * reached);
    (reaches(g) ? reached : missed) = g;
  }
  return out;
}

}  // namespace hapticd::analysis
