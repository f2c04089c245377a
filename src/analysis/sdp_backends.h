// The SDP libraries hapticd can use behind SdpSolver (sdp_solver.h).
#pragma once

#include <memory>

#include "analysis/sdp_solver.h"

namespace hapticd::analysis {

std::unique_ptr<SdpSolver> make_dsdp_solver();
std::unique_ptr<SdpSolver> make_csdp_solver();

}  // namespace hapticd::analysis
