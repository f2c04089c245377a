// The gate over a workspace (docs/math.md, several axes): for a device with several task axes,
// each wall's one-axis bound b_req (its K, B, T, delays, coupling) against the device's damping
// along the wall's normal, b_n(q) = 1 / (n^T J(q) B_j^-1 J(q)^T n), at the worst configuration
// where the wall can act (an attractor: against lambda_min(B_c(q)) everywhere, as it pulls every
// way, and b_req I in the matrix condition: its law runs along each task axis); and walls acting
// together (an edge, a corner) against the matrix condition B_c(q) - sum_i b_req_i n_i n_i^T >= 0.
// The workspace is sampled on a grid and the worst sample refined by a local search: what the grid
// can miss is measured (the largest change of b_n between neighbouring samples), not proven.
#pragma once

#include <string>
#include <vector>

#include "analysis/passivity.h"
#include "config/config.h"
#include "kinematics/pose.h"

namespace hapticd::gate {

// Samples per task axis of the grid: 17 (16 cells) keeps a delta's 4913 configurations under
// a tenth of a second.
inline constexpr int kWorkspaceSamples = 17;

struct WallVerdict {
  double required_damping = 0.0;    // b_req along the normal (+inf: no damping suffices)
  double available_damping = 0.0;   // (1 - passivity_margin) worst_damping: the most b_req may be
  double worst_damping = 0.0;       // least b_n where the wall can act, after refinement
                                    // (an attractor: least lambda_min(B_c) anywhere)
  double grid_worst_damping = 0.0;  // least b_n on the grid alone
  kinematics::Vec3 worst_position = kinematics::Vec3::Zero();  // x there (m)
  bool reached = false;                    // the wall can act somewhere in the workspace
  bool passive = false;                    // not reached, or b_req <= available_damping
  analysis::StiffnessLimit max_stiffness;  // the largest K that passes there
};

struct WorkspaceReport {
  std::vector<WallVerdict> walls;     // one per config walls entry
  std::vector<double> joint_damping;  // B_j's diagonal: device.damping of each joint
  int samples = 0;                    // grid configurations examined
  int outside = 0;  // of them, not a pose of the mechanism: refused (a wrong workspace box)
  // Least lambda_min(B_c - sum b_req_i / (1 - margin) n_i n_i^T) over the samples where two or
  // more walls act (+inf when nowhere), and where (N s/m).
  double corner_margin = 0.0;
  kinematics::Vec3 corner_position = kinematics::Vec3::Zero();
  // The largest relative change of b_n between neighbouring grid samples where a wall acts:
  // how much the refinement had to find between them (0 for a constant Jacobian).
  double neighbour_change = 0.0;
  // J does not depend on q (joints, cartesian): b_n is the same everywhere, and an unbounded
  // workspace is sampled around the walls, where they meet.
  bool configuration_independent = false;
  bool pass = false;
  std::vector<std::string> reasons;
  // Whether a client may move the walls (docs/operations.md, scene requests: move) with no new
  // gate: they pass where they are, each passes wherever in the workspace it could be put, and
  // all of them pass acting at once anywhere (moved walls may meet, even overlap). Otherwise
  // `not_movable` says the first reason, with its numbers.
  bool movable = false;
  std::string not_movable;
};

// Not RT-safe. Pure function of cfg (its walls, kinematics, device damping per joint, T,
// delays, safety margins) and the driver's delay.
WorkspaceReport evaluate_workspace(const config::Config& cfg, int device_delay_samples);

}  // namespace hapticd::gate
