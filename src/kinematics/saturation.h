// Joint torque saturation that keeps the force's direction: when some joint would exceed its
// limit the whole torque vector is scaled down by one factor, so the largest excess lands
// exactly on its limit and the force the device renders turns neither way (clipping each joint
// alone would).
#pragma once

#include "kinematics/pose.h"

namespace hapticd::kinematics {

enum class SaturationStatus {
  kWithin,     // every joint within its limit: tau unchanged
  kSaturated,  // scaled down by `scale` < 1
  kNonFinite,  // a non-finite torque or limit, or a negative limit: zero torque
};

struct Saturated {
  SaturationStatus status = SaturationStatus::kWithin;
  Vec3 tau = Vec3::Zero();  // first n entries
  double scale = 1.0;       // what tau was multiplied by (0 for kNonFinite)
};

// RT-safe: called every tick. `limit` per joint (>= 0, in the joints' torque units).
Saturated saturate(const Vec3& tau, const Vec3& limit, int n) noexcept;

}  // namespace hapticd::kinematics
