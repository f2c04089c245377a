// Linear matrix inequalities over a vector y of real decision variables, and the semidefinite
// program a solver is handed: minimise c'y subject to F_b(y) >= 0 for every block b, where
// each F_b(y) = F_b0 + sum_k y_k F_bk is symmetric. The coupling design (coupling_synthesis.h)
// writes Naghshtabrizi and Hespanha's LMIs in these terms; sdp_solver.h solves them. Not
// RT-safe (allocates).
#pragma once

#include <Eigen/Dense>
#include <initializer_list>
#include <utility>
#include <vector>

namespace hapticd::analysis {

// M(y) = constant + sum over terms of y[var] * coefficient: a matrix affine in y.
struct AffineMatrix {
  Eigen::MatrixXd constant;
  std::vector<std::pair<int, Eigen::MatrixXd>> terms;  // one per variable, no repeats

  Eigen::Index rows() const { return constant.rows(); }
  Eigen::Index cols() const { return constant.cols(); }
};

AffineMatrix affine(const Eigen::MatrixXd& constant);
AffineMatrix operator+(const AffineMatrix& a, const AffineMatrix& b);
AffineMatrix operator*(const Eigen::MatrixXd& left, const AffineMatrix& m);
AffineMatrix operator*(const AffineMatrix& m, const Eigen::MatrixXd& right);
AffineMatrix operator*(double k, const AffineMatrix& m);
AffineMatrix transpose(const AffineMatrix& m);
// Rows of blocks, each row the same height, each column the same width.
AffineMatrix affine_blocks(std::initializer_list<std::initializer_list<AffineMatrix>> rows);
Eigen::MatrixXd evaluate(const AffineMatrix& m, const Eigen::VectorXd& y);

// Hands out decision variables in order.
class VariablePool {
 public:
  int scalar() { return next_++; }
  // A symmetric n x n matrix of n (n + 1) / 2 fresh variables (row >= column order).
  AffineMatrix symmetric(int n);
  // A 1 x n row of fresh variables.
  AffineMatrix row(int n);
  int count() const { return next_; }

 private:
  int next_ = 0;
};

// y'F_k entries of one symmetric block, lower triangle only (row >= col); var -1 is F_0.
struct LmiEntry {
  int var = -1;
  int row = 0;
  int col = 0;
  double value = 0.0;
};

struct LmiBlock {
  int size = 0;
  std::vector<LmiEntry> entries;  // at most one per (var, row, col)
};

// [M_00 M_10' ...; M_10 M_11 ...; ...] >= 0 from the blocks on and below the diagonal (those
// on the diagonal must be symmetric; blocks never set are zero).
LmiBlock lmi_block(std::initializer_list<int> sizes,
                   std::initializer_list<std::pair<std::pair<int, int>, AffineMatrix>> parts);

// The symmetric matrix F(y) of a block (for checks and tests).
Eigen::MatrixXd evaluate(const LmiBlock& block, const Eigen::VectorXd& y);

struct SdpProblem {
  int variables = 0;
  Eigen::VectorXd objective;  // c: minimise c'y
  std::vector<LmiBlock> blocks;
  // Each F_b(y) >= margin I: a strict inequality made one a solver can certify.
  double margin = 0.0;
};

}  // namespace hapticd::analysis
