// DSDP 5.8 (S. J. Benson and Y. Ye, the dual-scaling interior-point method; Debian's
// libdsdp-dev) behind SdpSolver. DSDP's problem is the LMI form itself: maximise b'y subject
// to C - sum_i y_i A_i >= 0, one packed lower triangle per block and variable; it prints
// nothing unless a monitor is set.
#include <dsdp/dsdp5.h>

#include <cmath>
#include <vector>

#include "analysis/sdp_backends.h"

namespace hapticd::analysis {
namespace {

// Owns the handle; DSDP keeps pointers to the data arrays, which must outlive DSDPSolve.
struct Handle {
  DSDP dsdp = nullptr;
  ~Handle() {
    if (dsdp != nullptr) DSDPDestroy(dsdp);
  }
};

struct BlockData {  // per variable 0..m (0: C), the packed indices and values of one block
  std::vector<std::vector<int>> index;
  std::vector<std::vector<double>> value;
};

BlockData pack(const LmiBlock& block, int variables, double margin) {
  BlockData d;
  d.index.resize(static_cast<std::size_t>(variables) + 1);
  d.value.resize(static_cast<std::size_t>(variables) + 1);
  // DSDP: C - sum y_i A_i >= 0. Ours: F0 - margin I + sum y_k F_k >= 0, so C = F0 - margin I
  // and A_i = -F_i.
  std::vector<double> diagonal_shift(static_cast<std::size_t>(block.size), -margin);
  for (const LmiEntry& e : block.entries) {
    const std::size_t slot = static_cast<std::size_t>(e.var + 1);
    const int packed = e.row * (e.row + 1) / 2 + e.col;
    double v = e.var < 0 ? e.value : -e.value;
    if (e.var < 0 && e.row == e.col) {
      v += diagonal_shift[static_cast<std::size_t>(e.row)];
      diagonal_shift[static_cast<std::size_t>(e.row)] = 0.0;
    }
    d.index[slot].push_back(packed);
    d.value[slot].push_back(v);
  }
  for (int i = 0; i < block.size; ++i) {
    if (diagonal_shift[static_cast<std::size_t>(i)] != 0.0) {
      d.index[0].push_back(i * (i + 1) / 2 + i);
      d.value[0].push_back(diagonal_shift[static_cast<std::size_t>(i)]);
    }
  }
  return d;
}

class DsdpSolver final : public SdpSolver {
 public:
  SdpSolution solve(const SdpProblem& p) const override {
    SdpSolution s;
    const int m = p.variables;
    Handle h;
    SDPCone cone = nullptr;
    if (DSDPCreate(m, &h.dsdp) != 0 ||
        DSDPCreateSDPCone(h.dsdp, static_cast<int>(p.blocks.size()), &cone) != 0) {
      s.note = "DSDP: could not create the problem";
      return s;
    }
    std::vector<BlockData> data;
    data.reserve(p.blocks.size());
    for (std::size_t j = 0; j < p.blocks.size(); ++j) {
      const int bj = static_cast<int>(j), n = p.blocks[j].size;
      data.push_back(pack(p.blocks[j], m, p.margin));
      SDPConeSetBlockSize(cone, bj, n);
      for (int i = 0; i <= m; ++i) {
        const auto& idx = data.back().index[static_cast<std::size_t>(i)];
        if (idx.empty()) continue;
        SDPConeSetASparseVecMat(cone, bj, i, n, 1.0, 0, idx.data(),
                                data.back().value[static_cast<std::size_t>(i)].data(),
                                static_cast<int>(idx.size()));
      }
    }
    for (int i = 0; i < m; ++i) DSDPSetDualObjective(h.dsdp, i + 1, -p.objective(i));
    DSDPSetGapTolerance(h.dsdp, 1e-7);
    DSDPSetMaxIts(h.dsdp, 200);
    DSDPSetYBounds(h.dsdp, -1e9, 1e9);
    if (DSDPSetup(h.dsdp) != 0 || DSDPSolve(h.dsdp) != 0) {
      s.note = "DSDP: the solve failed";
      return s;
    }
    DSDPTerminationReason reason = CONTINUE_ITERATING;
    DSDPSolutionType type = DSDP_PDUNKNOWN;
    DSDPStopReason(h.dsdp, &reason);
    DSDPGetSolutionType(h.dsdp, &type);
    DSDPGetIts(h.dsdp, &s.iterations);
    s.y.resize(m);
    DSDPGetY(h.dsdp, s.y.data(), m);
    double dobj = 0.0;
    DSDPGetDObjective(h.dsdp, &dobj);
    s.objective = -dobj;
    if (type == DSDP_INFEASIBLE) {
      s.status = SdpSolution::Status::kInfeasible;
    } else if (reason == DSDP_CONVERGED && type == DSDP_PDFEASIBLE && s.y.allFinite()) {
      s.status = SdpSolution::Status::kSolved;
    } else {
      s.note = "DSDP stopped for reason " + std::to_string(static_cast<int>(reason)) +
               ", solution type " + std::to_string(static_cast<int>(type));
    }
    return s;
  }

  std::string name() const override { return "DSDP 5.8"; }
};

}  // namespace

std::unique_ptr<SdpSolver> make_dsdp_solver() { return std::make_unique<DsdpSolver>(); }

}  // namespace hapticd::analysis
