#include "analysis/coupling_design.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hapticd::analysis {
namespace {

bool finite_poly(const Polynomial& p) {
  return !p.empty() && std::all_of(p.begin(), p.end(), [](double v) { return std::isfinite(v); });
}

}  // namespace

void validate_coupling_spec(const CouplingSpec& s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(std::isfinite(s.sample_period) && s.sample_period > 0.0))
    fail("the sample period must be a finite number > 0");
  if (!(std::isfinite(s.device_damping) && s.device_damping > 0.0))
    fail("device.damping must be a finite number > 0: Theorem 1 divides by it");
  if (!(std::isfinite(s.allowed_damping) && s.allowed_damping > 0.0))
    fail(
        "the damping the gate allows ((1 - safety.passivity_margin) device.damping - "
        "safety.operator_passivity_shortage) must be > 0: no coupling can make b_req <= 0");
  if (s.order < 1 || s.order > kMaxDesignOrder)
    fail("the order must be 1 to " + std::to_string(kMaxDesignOrder) + ", got " +
         std::to_string(s.order));
  if (s.delay_samples < 0) fail("the delay must be >= 0 samples");
  for (const TransferFunction* tf : {&s.environment, &s.weight}) {
    if (!finite_poly(tf->num) || !finite_poly(tf->den) || tf->den[0] == 0.0)
      fail("the wall and the weight must have finite coefficients and den[0] != 0");
  }
  if (!is_stable(s.weight)) fail("the transparency weight W(z) must be stable");
  if (!is_stable(s.environment))
    fail(
        "E(z) has a pole on the unit circle (Tustin's at z = -1), so W (H - E) is unbounded "
        "for every coupling: design for wall.discretization: backward");
  if (poly_norm1(s.environment.num) == 0.0) fail("the wall is zero: there is nothing to couple");
}

namespace {

struct Candidate {
  CouplingFamily nu;
  TransferFunction coupling;
  CouplingVerdict verdict;
};

bool better(const CouplingVerdict& a, const CouplingVerdict& b) {
  if (a.valid() != b.valid()) return a.valid();
  return a.gamma < b.gamma;
}

// The family d z/(z-1) + D_c alone (C_bar = 0) at d, with the D_c (a few multiples of T/(2b))
// that passes best; its verdict is invalid when none passes.
Candidate family_at(const CouplingSpec& spec, double d) {
  const double unit = spec.sample_period / (2.0 * spec.device_damping);
  Candidate best;
  for (double m : {0.5, 1.0, 1.5, 2.0, 4.0}) {
    const CouplingFamily nu{d, unit * m};
    const TransferFunction c = coupling_filter_of({}, nu, {});
    Candidate cand{nu, c, evaluate_coupling(spec, c)};
    if (m == 0.5 || better(cand.verdict, best.verdict)) best = cand;
  }
  return best;
}

// family_at on a grid of d around T/(2b), those that pass, best first.
std::vector<Candidate> screen_families(const CouplingSpec& spec) {
  const double unit = spec.sample_period / (2.0 * spec.device_damping);
  std::vector<Candidate> out;
  for (int k = -6; k <= 4; ++k) {
    Candidate c = family_at(spec, unit * std::pow(10.0, 0.5 * k));
    if (c.verdict.valid()) out.push_back(c);
  }
  std::stable_sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return better(a.verdict, b.verdict);
  });
  return out;
}

// Up to n of the screened families whose d lie at least a decade apart, best first: where the
// search starts cone complementarity runs.
std::vector<Candidate> probes(const std::vector<Candidate>& screened, std::size_t n) {
  std::vector<Candidate> out;
  for (const Candidate& c : screened) {
    const bool apart = std::all_of(out.begin(), out.end(), [&](const Candidate& o) {
      return std::abs(std::log10(c.nu.d / o.nu.d)) > 0.99;
    });
    if (apart) out.push_back(c);
    if (out.size() == n) break;
  }
  return out;
}

// The next gamma to ask for inside the bracket [lo, hi].
double next_target(double lo, double hi) {
  if (lo <= 0.0) return 0.7 * hi;
  return std::sqrt(lo * hi);
}

// One nu with its LMIs, the best controller found there and the bracket of its gamma.
struct Site {
  Candidate best;
  CouplingLmis lmis;
  Eigen::VectorXd point;  // the best controller's SDP point: where the next run linearises
  double lo = 0.0;
};

class DesignSearch {
 public:
  DesignSearch(const CouplingSpec& spec, const DesignOptions& options, const SdpSolver& solver,
               const std::function<void(const DesignStep&)>& progress, CouplingDesign& out)
      : spec_(spec),
        options_(options),
        solver_(solver),
        progress_(progress),
        out_(out),
        scales_(coupling_scales(spec)) {}

  // A site at a family that passes alone, its LMIs linearised at C_bar = 0.
  Site open(const Candidate& c) {
    Site s{c, coupling_lmis(spec_, scales_, c.nu), {}, out_.gamma_floor};
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(spec_.order - 1);
    s.point = point_at(s.lmis, {zero, zero}, scales_.gamma_hat(c.verdict.gamma * 1.001), solver_);
    ++out_.sdp_solves;
    return s;
  }

  bool budget_left() const { return out_.steps < options_.max_steps; }
  bool closed(const Site& s) const {
    return s.best.verdict.gamma <= s.lo * (1.0 + options_.tolerance);
  }

  // One outer step: a cone complementarity run at the site toward the next target.
  void step(Site& s) {
    const double target = next_target(s.lo, s.best.verdict.gamma);
    CclRequest request;
    request.gamma = target;
    request.incumbent = s.best.verdict.gamma;
    request.max_iterations = options_.max_ccl_iterations;
    request.start = s.point.size() > 0 ? &s.point : nullptr;
    const CclResult r = cone_complementarity(spec_, scales_, s.best.nu, s.lmis, request, solver_);
    out_.sdp_solves += r.iterations;
    ++out_.steps;
    if (r.improved) {
      s.best = {s.best.nu, r.coupling, r.verdict};
      s.point = r.point;
    }
    // Not reached: certified (kInfeasible), or not in c iterations - the paper's stop. A
    // solver that gave up says nothing about the target.
    if (r.outcome == CclResult::Outcome::kInfeasible ||
        r.outcome == CclResult::Outcome::kNotConverged) {
      s.lo = std::max(s.lo, target);
    }
    if (progress_) {
      progress_({out_.steps,
                 s.best.nu,
                 target,
                 r.outcome,
                 r.iterations,
                 r.improved ? r.verdict.gamma : 0.0,
                 s.best.verdict.gamma,
                 s.lo,
                 DesignStep::Phase::kConeComplementarity,
                 {}});
    }
  }

 private:
  const CouplingSpec& spec_;
  const DesignOptions& options_;
  const SdpSolver& solver_;
  const std::function<void(const DesignStep&)>& progress_;
  CouplingDesign& out_;
  CouplingScales scales_;
};

}  // namespace

namespace {

// The cone complementarity stage at the spec's order (at most kConeComplementarityOrder): the
// family screen, a run at each of a few families a decade apart, a golden-section search of
// log d around the best, bisection of gamma at the best. Sets out's bracket and steps; false
// when its budget ran out first.
bool cone_complementarity_stage(const CouplingSpec& spec, const std::vector<Candidate>& screened,
                                const DesignOptions& options, const SdpSolver& solver,
                                const std::function<void(const DesignStep&)>& progress,
                                CouplingDesign& out, Candidate& best) {
  DesignSearch search(spec, options, solver, progress, out);
  std::vector<Site> sites;
  for (const Candidate& c : probes(screened, 4)) {
    if (!search.budget_left()) break;
    sites.push_back(search.open(c));
    search.step(sites.back());
  }
  const auto by_gamma = [](const Site& a, const Site& b) {
    return a.best.verdict.gamma < b.best.verdict.gamma;
  };
  const double d0 = std::min_element(sites.begin(), sites.end(), by_gamma)->best.nu.d;
  double a = std::log10(d0) - 1.0, b = std::log10(d0) + 1.0;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  const auto probe = [&](double x) {
    const Candidate c = family_at(spec, std::pow(10.0, x));
    if (!c.verdict.valid() || !search.budget_left()) return std::numeric_limits<double>::infinity();
    sites.push_back(search.open(c));
    search.step(sites.back());
    return sites.back().best.verdict.gamma;
  };
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = probe(x1), f2 = probe(x2);
  for (int i = 0; i < options.golden_steps && search.budget_left(); ++i) {
    if (f1 <= f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = probe(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = probe(x2);
    }
  }
  Site* site = &*std::min_element(sites.begin(), sites.end(), by_gamma);
  while (search.budget_left() && !search.closed(*site)) search.step(*site);
  best = site->best;
  out.gamma_lower = site->lo;
  return search.closed(*site);
}

// nu of a coupling with a pole at z = 1: d its residue there, D_c what is left at infinity.
CouplingFamily family_of(const TransferFunction& c) {
  const Polynomial rest = poly_deflate(c.den, 1.0);
  const double d = poly_eval(c.num, 1.0) / poly_eval(rest, 1.0);
  return {d, c.num.front() / c.den.front() - d};
}

}  // namespace

CouplingDesign design_coupling(const CouplingSpec& spec, const DesignOptions& options,
                               const SdpSolver& solver,
                               const std::function<void(const DesignStep&)>& progress) {
  validate_coupling_spec(spec);
  CouplingDesign out;
  const double w1 = dc_gain(spec.weight), e1 = dc_gain(spec.environment);
  out.gamma_floor = w1 * w1 * e1 * e1;
  const std::vector<Candidate> screened = screen_families(spec);
  if (screened.empty()) {
    out.status = CouplingDesign::Status::kNoCoupling;
    out.note = "no family d z/(z-1) + D_c passes on its own, so the search has no start";
    return out;
  }
  Candidate best = screened.front();
  bool closed = true;
  CouplingSpec seed_spec = spec;
  seed_spec.order = std::min(spec.order, kConeComplementarityOrder);
  if (seed_spec.order > 1) {
    closed = cone_complementarity_stage(seed_spec, screened, options, solver, progress, out, best);
  }
  out.gamma_seed = best.verdict.gamma;
  // At the floor no coupling does better (H(1) = 0): nothing is left to search.
  if (closed && best.verdict.gamma > out.gamma_floor * (1.0 + 1e-9)) {
    const int before = out.steps;
    const PoleSearchResult r = search_poles(spec, {best.coupling, best.verdict}, solver,
                                            options.poles, [&](const PoleSearchStep& p) {
                                              if (!progress) return;
                                              DesignStep s;
                                              s.phase = DesignStep::Phase::kPoles;
                                              s.index = before + p.index;
                                              s.best = p.best;
                                              s.poles = p;
                                              progress(s);
                                            });
    out.steps += r.steps;
    out.sdp_solves += r.sdp_solves;
    best = {family_of(r.best.coupling), r.best.coupling, r.best.verdict};
    if (!r.converged) {
      closed = false;
      out.note = "the pole search did not converge within its " +
                 std::to_string(options.poles.max_steps) + " sweeps";
    }
  } else if (!closed) {
    out.note = "gamma's bracket did not close within the step budget";
  }
  out.coupling = best.coupling;
  out.nu = best.nu;
  out.verdict = best.verdict;
  out.status = closed ? CouplingDesign::Status::kDesigned : CouplingDesign::Status::kNotConverged;
  return out;
}

}  // namespace hapticd::analysis
