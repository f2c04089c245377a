#include "analysis/coupling_lmis.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace hapticd::analysis {
namespace {

using Eigen::MatrixXd;

MatrixXd scalar(double v) { return MatrixXd::Constant(1, 1, v); }

// The closed loop of a plant with inputs (w, u) and outputs (z, y) and the controller
// x_c+ = A_c x_c + e1 y, u = C_c x_c, affine in A_c and C_c (their (16)).
AffineSystem close_loop(const StateSpace& p, const AffineMatrix& ac, const AffineMatrix& cc) {
  const Eigen::Index nc = ac.rows();
  const MatrixXd bw = p.b.col(0), bu = p.b.col(1);
  const MatrixXd co = p.c.row(0), c1 = p.c.row(1);
  const double dow = p.d(0, 0), dou = p.d(0, 1), d1w = p.d(1, 0), d1u = p.d(1, 1);
  MatrixXd e1 = MatrixXd::Zero(nc, 1);
  e1(0, 0) = 1.0;
  AffineSystem cl;
  cl.a = affine_blocks({{affine(p.a), bu * cc}, {affine(e1 * c1), ac + (d1u * e1) * cc}});
  cl.b = affine_blocks({{affine(bw)}, {affine(d1w * e1)}});
  cl.c = affine_blocks({{affine(co), dou * cc}});
  cl.d = affine(scalar(dow));
  return cl;
}

// [X, C', A'; C, D + D', B'; A, B, Y] >= 0: Lemma 1 applied to the positive-real condition.
LmiBlock positive_real(const MatrixPair& xy, const AffineSystem& s) {
  const int n = static_cast<int>(s.a.rows());
  return lmi_block({n, 1, n}, {{{0, 0}, xy.x},
                               {{1, 0}, s.c},
                               {{1, 1}, s.d + transpose(s.d)},
                               {{2, 0}, s.a},
                               {{2, 1}, s.b},
                               {{2, 2}, xy.y}});
}

LmiBlock complementary(const MatrixPair& xy) {
  const int n = static_cast<int>(xy.x.rows());
  return lmi_block({n, n},
                   {{{0, 0}, xy.x}, {{1, 0}, affine(MatrixXd::Identity(n, n))}, {{1, 1}, xy.y}});
}

}  // namespace

CouplingScales coupling_scales(const CouplingSpec& spec) {
  double e = 0.0, we = 0.0;
  for (int i = 0; i <= 256; ++i) {
    const double th = std::numbers::pi * i / 256.0;
    const Complex ei = frequency_response(spec.environment, th);
    e = std::max(e, std::abs(ei));
    we = std::max(we, std::abs(frequency_response(spec.weight, th) * ei));
  }
  return {e, we > 0.0 ? e / we : 1.0};
}

TransferFunction coupling_filter_of(const CouplingScales& scales, const CouplingFamily& nu,
                                    const CouplingParameters& chi) {
  // C = C_bar + d/(1 - w) + D_c = [(Nb + D_c Db)(1 - w) + d Db] / (Db (1 - w)), w = z^-1.
  Polynomial nb{0.0}, db{1.0};
  for (Eigen::Index i = 0; i < chi.alpha.size(); ++i) {
    nb.push_back(chi.c(i) / scales.force);
    db.push_back(chi.alpha(i));
  }
  const Polynomial num =
      poly_add(poly_mul(poly_add(nb, poly_scale(db, nu.dc)), {1.0, -1.0}), poly_scale(db, nu.d));
  return {poly_trim(num), poly_trim(poly_mul(db, {1.0, -1.0}))};
}

CouplingPlants coupling_plants(const CouplingSpec& spec, const CouplingScales& scales,
                               const CouplingFamily& nu) {
  const double scale = scales.force;
  const TransferFunction e = tf_scale(spec.environment, 1.0 / scale);
  const double d = nu.d * scale, dc = nu.dc * scale;
  // G2 = E / (1 + E (d/(1 - w) + D_c)) = n (1 - w) / den2, and G2 / (z - 1) = n w / den2.
  const Polynomial den2 = poly_add(poly_mul(e.den, {1.0, -1.0}), poly_mul(e.num, {d + dc, -dc}));
  const Polynomial g2 = poly_mul(e.num, {1.0, -1.0});
  CouplingPlants p;
  const MatrixXd split_inputs{{1.0, -1.0}, {1.0, 0.0}};  // (w, u) -> (w - u, w)
  StateSpace s = mix_inputs(append(realise({g2}, den2), realise({e.num}, e.den)), split_inputs);
  s = mix_outputs(MatrixXd{{1.0, -1.0}, {1.0, 0.0}}, s);  // (f, E w) -> (f - E w, f)
  const Polynomial w = poly_scale(spec.weight.num, scales.weight);
  p.transparency = balanced(
      series(s, append(realise({w}, spec.weight.den), static_gain(MatrixXd::Identity(1, 1)))));
  const double kappa = spec.sample_period * scale / spec.allowed_damping;
  const Polynomial delayed = poly_scale(poly_shift(e.num, 1 + spec.delay_samples), kappa);
  p.passivity = balanced(mix_inputs(realise({delayed, g2}, den2), MatrixXd{{1.0, -1.0}}));
  return p;
}

CouplingLmis coupling_lmis(const CouplingSpec& spec, const CouplingScales& scales,
                           const CouplingFamily& nu) {
  const double scale = scales.force;
  if (spec.order < 2) throw std::invalid_argument("coupling_lmis: order 1 has no C_bar");
  CouplingLmis l;
  const CouplingPlants plants = coupling_plants(spec, scales, nu);
  const int nc = spec.order - 1;
  const int n1 = static_cast<int>(plants.transparency.states()) + nc;
  const int n3 = static_cast<int>(plants.passivity.states()) + nc;
  VariablePool pool;
  const std::array<int, 3> sizes{n1, nc + 1, n3};
  for (std::size_t i = 0; i < 3; ++i) {
    l.pairs[i].x = pool.symmetric(sizes[i]);
    l.pairs[i].y = pool.symmetric(sizes[i]);
  }
  // A_c: companion form, first row -alpha; C_c = c.
  AffineMatrix ac{MatrixXd::Zero(nc, nc), {}};
  for (int i = 1; i < nc; ++i) ac.constant(i, i - 1) = 1.0;
  for (int i = 0; i < nc; ++i) {
    l.alpha.push_back(pool.scalar());
    MatrixXd e = MatrixXd::Zero(nc, nc);
    e(0, i) = -1.0;
    ac.terms.emplace_back(l.alpha.back(), e);
  }
  const AffineMatrix cc = pool.row(nc);
  for (const auto& term : cc.terms) l.c.push_back(term.first);
  l.variables = pool.count();

  l.systems[0] = close_loop(plants.transparency, ac, cc);
  const AffineSystem& t = l.systems[0];
  l.transparency = lmi_block({n1, 1, n1, 1}, {{{0, 0}, l.pairs[0].x},
                                              {{2, 0}, t.a},
                                              {{2, 1}, t.b},
                                              {{2, 2}, l.pairs[0].y},
                                              {{3, 0}, t.c},
                                              {{3, 1}, t.d},
                                              {{3, 3}, affine(scalar(1.0))}});
  l.gamma_row = n1;

  // Theorem 1: (1 - w)(C_bar + D_c - beta) + d, normalised: beta = s T / (2 b).
  const double beta = scale * spec.sample_period / (2.0 * spec.device_damping);
  const double dc = nu.dc * scale - beta;
  MatrixXd e1 = MatrixXd::Zero(nc, 1);
  if (nc > 0) e1(0, 0) = 1.0;
  const AffineMatrix abar =
      affine_blocks({{ac, affine(-e1)}, {affine(MatrixXd::Zero(1, nc)), affine(scalar(0.0))}});
  MatrixXd bbar(nc + 1, 1);
  bbar << e1, 1.0;
  const AffineMatrix cbar = affine_blocks({{cc, affine(scalar(-dc))}});
  l.systems[1] = {abar, affine(bbar), cbar, affine(scalar(dc + nu.d * scale))};
  l.theorem1 = positive_real(l.pairs[1], l.systems[1]);

  l.systems[2] = close_loop(plants.passivity, ac, cc);
  l.systems[2].d = l.systems[2].d + affine(scalar(1.0));
  l.passivity = positive_real(l.pairs[2], l.systems[2]);
  for (std::size_t i = 0; i < 3; ++i) l.couplings[i] = complementary(l.pairs[i]);
  return l;
}

SdpProblem coupling_sdp(const CouplingLmis& lmis, double gamma_hat, const Eigen::VectorXd& c) {
  SdpProblem p;
  p.variables = lmis.variables;
  p.objective = c;
  p.blocks = {lmis.transparency, lmis.theorem1, lmis.passivity};
  p.blocks[0].entries.push_back({-1, lmis.gamma_row, lmis.gamma_row, gamma_hat});
  for (const LmiBlock& b : lmis.couplings) p.blocks.push_back(b);
  return p;
}

CouplingParameters parameters_at(const CouplingLmis& lmis, const Eigen::VectorXd& y) {
  CouplingParameters chi;
  chi.alpha.resize(static_cast<Eigen::Index>(lmis.alpha.size()));
  chi.c.resize(static_cast<Eigen::Index>(lmis.c.size()));
  for (std::size_t i = 0; i < lmis.alpha.size(); ++i) {
    chi.alpha(static_cast<Eigen::Index>(i)) = y(lmis.alpha[i]);
    chi.c(static_cast<Eigen::Index>(i)) = y(lmis.c[i]);
  }
  return chi;
}

}  // namespace hapticd::analysis
