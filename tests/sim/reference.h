// Independent high-accuracy reference for the plant tests: classical RK4 on the continuous
// model m v' = -b v + u + f_op with fine substeps, integrating the operator's work
// W' = f_op v as a third state. It shares no code with sim/ (its own piecewise-linear
// evaluation), so agreement is evidence, not a tautology.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

namespace hapticd::sim::testref {

struct Params {
  double m = 0.1;
  double b = 2.0;
  bool hand = true;  // hand: f_op = kh (s - x) - bh v; otherwise f_op = s (force profile)
  double kh = 0.0;
  double bh = 0.0;
};

struct State {
  double x = 0.0;
  double v = 0.0;
  double w = 0.0;  // work done by the operator
};

// Piecewise-linear (t, value) points, held at both ends; equal times make a jump.
// On an interval (a, b) containing no point strictly inside, the function is affine; this
// returns it as a callable so the integrator never evaluates across a kink or jump.
inline std::function<double(double)> affine_on(const std::vector<std::pair<double, double>>& pts,
                                               double a, double b) {
  int i = -1;  // last point at or before a
  for (int k = 0; k < static_cast<int>(pts.size()); ++k) {
    if (pts[static_cast<std::size_t>(k)].first <= a) i = k;
  }
  int j = -1;  // first point at or after b
  for (int k = static_cast<int>(pts.size()) - 1; k >= 0; --k) {
    if (pts[static_cast<std::size_t>(k)].first >= b) j = k;
  }
  if (i < 0) return [v = pts.front().second](double) { return v; };
  if (j < 0) return [v = pts.back().second](double) { return v; };
  // Plain copies, not structured bindings: clang before 16 cannot capture those.
  const std::pair<double, double> pa = pts[static_cast<std::size_t>(i)];
  const std::pair<double, double> pb = pts[static_cast<std::size_t>(j)];
  return [pa, pb](double t) {
    return pa.second + (pb.second - pa.second) * (t - pa.first) / (pb.first - pa.first);
  };
}

inline double operator_force(const Params& p, double s, double x, double v) {
  return p.hand ? p.kh * (s - x) - p.bh * v : s;
}

// Integrates [a, b] with n RK4 steps; s gives the profile value on that interval.
inline State rk4(const Params& p, State y, double a, double b, int n, double u,
                 const std::function<double(double)>& s) {
  const double h = (b - a) / n;
  auto f = [&](double t, const State& q) {
    const double fop = operator_force(p, s(t), q.x, q.v);
    return State{q.v, (-p.b * q.v + u + fop) / p.m, fop * q.v};
  };
  auto add = [](const State& q, double c, const State& d) {
    return State{q.x + c * d.x, q.v + c * d.v, q.w + c * d.w};
  };
  for (int i = 0; i < n; ++i) {
    const double t = a + i * h;
    const State k1 = f(t, y);
    const State k2 = f(t + h / 2, add(y, h / 2, k1));
    const State k3 = f(t + h / 2, add(y, h / 2, k2));
    const State k4 = f(t + h, add(y, h, k3));
    y = State{y.x + h / 6 * (k1.x + 2 * k2.x + 2 * k3.x + k4.x),
              y.v + h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v),
              y.w + h / 6 * (k1.w + 2 * k2.w + 2 * k3.w + k4.w)};
  }
  return y;
}

// States at the sample instants 0..u.size() with force u[k] held over period k. The profile is
// either the points (piecewise-linear, split exactly at every point) or, if pts is empty,
// the smooth function smooth(t). substep: the largest RK4 step.
inline std::vector<State> simulate(const Params& p, State y0, double period,
                                   const std::vector<double>& u,
                                   const std::vector<std::pair<double, double>>& pts,
                                   const std::function<double(double)>& smooth, double substep) {
  std::vector<State> out{y0};
  State y = y0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double t0 = static_cast<double>(k) * period;
    const double t1 = static_cast<double>(k + 1) * period;
    std::vector<double> cuts{t0};
    for (const auto& pt : pts) {
      if (pt.first > t0 && pt.first < t1) cuts.push_back(pt.first);
    }
    cuts.push_back(t1);
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
      const double a = cuts[c];
      const double b = cuts[c + 1];
      const int n = std::max(1, static_cast<int>(std::ceil((b - a) / substep)));
      y = rk4(p, y, a, b, n, u[k], pts.empty() ? smooth : affine_on(pts, a, b));
    }
    out.push_back(y);
  }
  return out;
}

}  // namespace hapticd::sim::testref
