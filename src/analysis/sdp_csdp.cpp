// CSDP 6.2 (B. Borchers, "CSDP, A C Library for Semidefinite Programming", Optimization Methods
// and Software, 1999; Debian's libsdp-dev) behind SdpSolver. CSDP's dual is the LMI form:
// minimise a'y subject to sum_i y_i A_i - C >= 0, blocks and indices from 1, constraint
// entries in the upper triangle. Its easy_sdp() reads param.csdp from the working directory and
// prints every iteration on stdout, so this calls sdp() itself with the parameters below and
// print level 0: nothing is read or printed.
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <vector>

extern "C" {
#include <csdp/declarations.h>
}

#include "analysis/sdp_backends.h"

namespace hapticd::analysis {
namespace {

// calloc'd (CSDP frees what it is given with free()).
template <typename T>
T* zeroed(std::size_t n) {
  return static_cast<T*>(std::calloc(n == 0 ? 1 : n, sizeof(T)));
}

paramstruc parameters() {
  paramstruc p{};
  p.axtol = 1e-8;  // CSDP's documented defaults, iteration limit 100
  p.atytol = 1e-8;
  p.objtol = 1e-8;
  p.pinftol = 1e8;
  p.dinftol = 1e8;
  p.maxiter = 100;
  p.minstepfrac = 0.90;
  p.maxstepfrac = 0.97;
  p.minstepp = 1e-8;
  p.minstepd = 1e-8;
  p.usexzgap = 1;
  p.tweakgap = 0;
  p.affine = 0;
  p.perturbobj = 1;
  p.fastmode = 0;
  return p;
}

// The problem in CSDP's structures: C = -(F0 - margin I), A_i = F_i, a = c.
struct Problem {
  int n = 0;
  int k = 0;
  blockmatrix c{};
  double* a = nullptr;
  constraintmatrix* constraints = nullptr;
};

// One variable's entries in one LMI block as CSDP's sparse block, prepended to that
// variable's constraint list (so each list ends up in block order).
void add_entries(Problem& q, int b, int size, bool diagonal, int v,
                 const std::vector<const LmiEntry*>& list) {
  auto* sb = zeroed<sparseblock>(1);
  sb->blocknum = b;
  sb->blocksize = size;
  sb->constraintnum = v + 1;
  sb->numentries = static_cast<int>(list.size());
  sb->entries = zeroed<double>(list.size() + 1);
  sb->iindices = zeroed<int>(list.size() + 1);
  sb->jindices = zeroed<int>(list.size() + 1);
  for (std::size_t e = 0; e < list.size(); ++e) {
    sb->entries[e + 1] = list[e]->value;
    sb->iindices[e + 1] = list[e]->col + 1;  // upper triangle: i <= j
    sb->jindices[e + 1] = list[e]->row + 1;
  }
  // Dense storage when the block is well filled (CSDP's own rule of thumb for its Schur
  // complement products).
  const double kk = q.k, nnz = static_cast<double>(list.size()), sz = size;
  sb->issparse =
      (!diagonal && kk * kk * nnz * nnz > 0.125 * kk * sz * sz * sz && list.size() > 5) ? 0 : 1;
  sb->next = q.constraints[v + 1].blocks;
  q.constraints[v + 1].blocks = sb;
}

// LMI block b (1-based): its constant part into C, its variables' parts into the constraints.
void convert_block(const SdpProblem& p, int b, Problem& q) {
  const LmiBlock& blk = p.blocks[static_cast<std::size_t>(b - 1)];
  const int size = blk.size;
  q.n += size;
  blockrec& rec = q.c.blocks[b];
  rec.blocksize = size;
  // A block of scalar inequalities (only diagonal entries) is CSDP's DIAG: linear in its
  // size, where a dense MATRIX block costs its cube per iteration.
  const bool diagonal = std::all_of(blk.entries.begin(), blk.entries.end(),
                                    [](const LmiEntry& e) { return e.row == e.col; });
  rec.blockcategory = diagonal ? DIAG : MATRIX;
  const std::size_t stored = diagonal
                                 ? static_cast<std::size_t>(size) + 1
                                 : static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
  double* data = zeroed<double>(stored);
  (diagonal ? rec.data.vec : rec.data.mat) = data;
  const auto at = [&](int i, int j) -> double& { return data[diagonal ? i : ijtok(i, j, size)]; };
  for (int i = 1; i <= size; ++i) at(i, i) = p.margin;
  std::vector<std::vector<const LmiEntry*>> per_var(static_cast<std::size_t>(q.k));
  for (const LmiEntry& e : blk.entries) {
    if (e.var >= 0) {
      per_var[static_cast<std::size_t>(e.var)].push_back(&e);
      continue;
    }
    at(e.row + 1, e.col + 1) -= e.value;
    if (e.row != e.col) at(e.col + 1, e.row + 1) -= e.value;
  }
  for (int v = 0; v < q.k; ++v) {
    const auto& list = per_var[static_cast<std::size_t>(v)];
    if (!list.empty()) add_entries(q, b, size, diagonal, v, list);
  }
}

Problem convert(const SdpProblem& p) {
  Problem q;
  q.k = p.variables;
  const int nb = static_cast<int>(p.blocks.size());
  q.c.nblocks = nb;
  q.c.blocks = zeroed<blockrec>(static_cast<std::size_t>(nb) + 1);
  q.a = zeroed<double>(static_cast<std::size_t>(q.k) + 1);
  for (int i = 1; i <= q.k; ++i) q.a[i] = p.objective(i - 1);
  q.constraints = zeroed<constraintmatrix>(static_cast<std::size_t>(q.k) + 1);
  for (int b = nb; b >= 1; --b) convert_block(p, b, q);  // prepended: lists end in block order
  return q;
}

// Links each block's entries across constraints (nextbyblock) and returns, per block, the
// first of them: the structure sdp() walks to build its Schur complement.
std::vector<sparseblock*> link_by_block(const Problem& q) {
  std::vector<sparseblock*> first(static_cast<std::size_t>(q.c.nblocks) + 1, nullptr);
  std::vector<sparseblock*> last(first.size(), nullptr);
  for (int i = 1; i <= q.k; ++i) {
    for (sparseblock* p = q.constraints[i].blocks; p != nullptr; p = p->next) {
      p->nextbyblock = nullptr;
      const auto b = static_cast<std::size_t>(p->blocknum);
      (last[b] != nullptr ? last[b]->nextbyblock : first[b]) = p;
      last[b] = p;
    }
  }
  return first;
}

// The workspace sdp() needs, freed on every path.
struct Work {
  explicit Work(const Problem& q) : m(q.n > q.k ? q.n : q.k), ldam(q.k % 2 == 0 ? q.k + 1 : q.k) {
    for (blockmatrix* b : {&work1, &work2, &work3, &zi, &dz, &dx}) alloc_mat(q.c, b);
    for (blockmatrix* b : {&bestx, &bestz, &cholxinv, &cholzinv}) alloc_mat_packed(q.c, b);
    for (auto& v : vec) v.assign(static_cast<std::size_t>(m) + 1, 0.0);
    for (auto& v : kvec) v.assign(static_cast<std::size_t>(q.k) + 1, 0.0);
    o.assign(static_cast<std::size_t>(ldam) * static_cast<std::size_t>(ldam), 0.0);
  }
  ~Work() {
    for (blockmatrix* b : {&work1, &work2, &work3, &zi, &dz, &dx}) free_mat(*b);
    for (blockmatrix* b : {&bestx, &bestz, &cholxinv, &cholzinv}) free_mat_packed(*b);
  }
  Work(const Work&) = delete;
  Work& operator=(const Work&) = delete;
  int m, ldam;
  blockmatrix work1{}, work2{}, work3{}, zi{}, dz{}, dx{};
  blockmatrix bestx{}, bestz{}, cholxinv{}, cholzinv{};
  std::vector<double> vec[9];   // workvec1..8, diagO
  std::vector<double> kvec[5];  // besty, rhs, dy, dy1, Fp
  std::vector<double> o;
};

void free_fill(constraintmatrix fill) {
  for (sparseblock* p = fill.blocks; p != nullptr;) {
    sparseblock* next = p->next;
    std::free(p->entries);
    std::free(p->iindices);
    std::free(p->jindices);
    std::free(p);
    p = next;
  }
}

class CsdpSolver final : public SdpSolver {
 public:
  SdpSolution solve(const SdpProblem& p) const override {
    SdpSolution s;
    Problem q = convert(p);
    blockmatrix x{}, z{};
    double* y = nullptr;
    int ret = -1;
    double pobj = 0.0, dobj = 0.0;
    bool every_variable_used = true;
    for (int v = 1; v <= q.k; ++v) every_variable_used &= q.constraints[v].blocks != nullptr;
    if (every_variable_used && q.k > 0) {  // sdp() needs each constraint non-empty
      std::vector<sparseblock*> byblocks = link_by_block(q);
      initsoln(q.n, q.k, q.c, q.a, q.constraints, &x, &y, &z);
      Work w(q);
      constraintmatrix fill{};
      makefill(q.k, q.c, q.constraints, &fill, w.work1, 0);
      sort_entries(q.k, q.c, q.constraints);
      auto v = [&](int i) { return w.vec[i].data(); };
      auto kv = [&](int i) { return w.kvec[i].data(); };
      ret = sdp(q.n, q.k, q.c, q.a, 0.0, q.constraints, byblocks.data(), fill, x, y, z, w.cholxinv,
                w.cholzinv, &pobj, &dobj, w.work1, w.work2, w.work3, v(0), v(1), v(2), v(3), v(4),
                v(5), v(6), v(7), v(8), w.bestx, kv(0), w.bestz, w.zi, w.o.data(), kv(1), w.dz,
                w.dx, kv(2), kv(3), kv(4), 0, parameters());
      free_fill(fill);
      s.y.resize(q.k);
      for (int i = 0; i < q.k; ++i) s.y(i) = y[i + 1];
      s.objective = dobj;
    } else {
      s.note = "CSDP: a variable appears in no block";
    }
    free_prob(q.n, q.k, q.c, q.a, q.constraints, x, y, z);
    // 0 solved, 3 solved to reduced accuracy (the design checks every answer exactly), 2 the
    // LMIs (CSDP's dual) infeasible; anything else a failure.
    if ((ret == 0 || ret == 3) && s.y.allFinite()) {
      s.status = SdpSolution::Status::kSolved;
    } else if (ret == 2) {
      s.status = SdpSolution::Status::kInfeasible;
    } else if (ret >= 0) {
      s.note = "CSDP returned " + std::to_string(ret);
    }
    return s;
  }

  std::string name() const override { return "CSDP 6.2"; }
};

}  // namespace

std::unique_ptr<SdpSolver> make_csdp_solver() { return std::make_unique<CsdpSolver>(); }
std::unique_ptr<SdpSolver> make_sdp_solver() { return make_csdp_solver(); }

}  // namespace hapticd::analysis
