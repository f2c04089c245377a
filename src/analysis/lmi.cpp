#include "analysis/lmi.h"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>

namespace hapticd::analysis {
namespace {

using Eigen::MatrixXd;

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("lmi: ") + what);
}

// Applies f to the constant and to every coefficient.
template <typename F>
AffineMatrix map(const AffineMatrix& m, F f) {
  AffineMatrix r{f(m.constant), {}};
  r.terms.reserve(m.terms.size());
  for (const auto& [var, coeff] : m.terms) r.terms.emplace_back(var, f(coeff));
  return r;
}

}  // namespace

AffineMatrix affine(const MatrixXd& constant) { return {constant, {}}; }

AffineMatrix operator+(const AffineMatrix& a, const AffineMatrix& b) {
  require(a.rows() == b.rows() && a.cols() == b.cols(), "sum of matrices of different sizes");
  std::map<int, MatrixXd> terms;
  for (const auto& [var, coeff] : a.terms) terms.emplace(var, coeff);
  for (const auto& [var, coeff] : b.terms) {
    auto [it, fresh] = terms.emplace(var, coeff);
    if (!fresh) it->second += coeff;
  }
  AffineMatrix r{a.constant + b.constant, {}};
  r.terms.assign(terms.begin(), terms.end());
  return r;
}

AffineMatrix operator*(const MatrixXd& left, const AffineMatrix& m) {
  require(left.cols() == m.rows(), "product of mismatched sizes");
  return map(m, [&](const MatrixXd& x) -> MatrixXd { return left * x; });
}

AffineMatrix operator*(const AffineMatrix& m, const MatrixXd& right) {
  require(m.cols() == right.rows(), "product of mismatched sizes");
  return map(m, [&](const MatrixXd& x) -> MatrixXd { return x * right; });
}

AffineMatrix operator*(double k, const AffineMatrix& m) {
  return map(m, [&](const MatrixXd& x) -> MatrixXd { return k * x; });
}

AffineMatrix transpose(const AffineMatrix& m) {
  return map(m, [](const MatrixXd& x) -> MatrixXd { return x.transpose(); });
}

AffineMatrix affine_blocks(std::initializer_list<std::initializer_list<AffineMatrix>> rows) {
  Eigen::Index total_rows = 0, total_cols = 0;
  for (const auto& row : rows) total_rows += row.begin()->rows();
  for (const AffineMatrix& b : *rows.begin()) total_cols += b.cols();
  AffineMatrix r{MatrixXd::Zero(total_rows, total_cols), {}};
  std::map<int, MatrixXd> terms;
  Eigen::Index r0 = 0;
  for (const auto& row : rows) {
    Eigen::Index c0 = 0;
    const Eigen::Index h = row.begin()->rows();
    for (const AffineMatrix& b : row) {
      require(b.rows() == h, "blocks of one row differ in height");
      r.constant.block(r0, c0, h, b.cols()) = b.constant;
      for (const auto& [var, coeff] : b.terms) {
        auto it = terms.try_emplace(var, MatrixXd::Zero(total_rows, total_cols)).first;
        it->second.block(r0, c0, h, b.cols()) += coeff;
      }
      c0 += b.cols();
    }
    require(c0 == total_cols, "rows of blocks differ in width");
    r0 += h;
  }
  r.terms.assign(terms.begin(), terms.end());
  return r;
}

MatrixXd evaluate(const AffineMatrix& m, const Eigen::VectorXd& y) {
  MatrixXd r = m.constant;
  for (const auto& [var, coeff] : m.terms) r += y(var) * coeff;
  return r;
}

AffineMatrix VariablePool::symmetric(int n) {
  AffineMatrix r{MatrixXd::Zero(n, n), {}};
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) {
      MatrixXd e = MatrixXd::Zero(n, n);
      e(i, j) = e(j, i) = 1.0;
      r.terms.emplace_back(next_++, std::move(e));
    }
  }
  return r;
}

AffineMatrix VariablePool::row(int n) {
  AffineMatrix r{MatrixXd::Zero(1, n), {}};
  for (int j = 0; j < n; ++j) {
    MatrixXd e = MatrixXd::Zero(1, n);
    e(0, j) = 1.0;
    r.terms.emplace_back(next_++, std::move(e));
  }
  return r;
}

LmiBlock lmi_block(std::initializer_list<int> sizes,
                   std::initializer_list<std::pair<std::pair<int, int>, AffineMatrix>> parts) {
  std::vector<int> offset{0};
  for (int s : sizes) offset.push_back(offset.back() + s);
  const int nblocks = static_cast<int>(sizes.size());
  // (var, row, col) -> value, lower triangle.
  std::map<std::tuple<int, int, int>, double> acc;
  const auto put = [&](int var, const MatrixXd& x, int bi, int bj) {
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      for (Eigen::Index j = 0; j < x.cols(); ++j) {
        const int row = offset[bi] + static_cast<int>(i), col = offset[bj] + static_cast<int>(j);
        if (row < col || x(i, j) == 0.0) continue;  // the diagonal block's upper half: mirror
        acc[{var, row, col}] += x(i, j);
      }
    }
  };
  for (const auto& [where, m] : parts) {
    const auto [bi, bj] = where;
    require(bi >= bj && bi < nblocks, "a block above the diagonal or outside the matrix");
    require(m.rows() == offset[bi + 1] - offset[bi] && m.cols() == offset[bj + 1] - offset[bj],
            "a block of the wrong size");
    put(-1, m.constant, bi, bj);
    for (const auto& [var, coeff] : m.terms) put(var, coeff, bi, bj);
  }
  LmiBlock b;
  b.size = offset.back();
  b.entries.reserve(acc.size());
  for (const auto& [key, value] : acc) {
    if (value == 0.0) continue;
    const auto [var, row, col] = key;
    b.entries.push_back({var, row, col, value});
  }
  return b;
}

MatrixXd evaluate(const LmiBlock& block, const Eigen::VectorXd& y) {
  MatrixXd f = MatrixXd::Zero(block.size, block.size);
  for (const LmiEntry& e : block.entries) {
    const double v = e.var < 0 ? e.value : e.value * y(e.var);
    f(e.row, e.col) += v;
    if (e.row != e.col) f(e.col, e.row) += v;
  }
  return f;
}

}  // namespace hapticd::analysis
