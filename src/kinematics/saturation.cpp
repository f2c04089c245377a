#include "kinematics/saturation.h"

#include <algorithm>
#include <cmath>

namespace hapticd::kinematics {

Saturated saturate(const Vec3& tau, const Vec3& limit, int n) noexcept {
  Saturated out;
  double scale = 1.0;
  for (int i = 0; i < n; ++i) {
    const double t = std::abs(tau[i]);
    if (!std::isfinite(t) || !std::isfinite(limit[i]) || !(limit[i] >= 0)) {
      out.status = SaturationStatus::kNonFinite;
      out.scale = 0.0;
      return out;
    }
    if (t > limit[i]) scale = std::fmin(scale, limit[i] / t);
  }
  for (int i = 0; i < n; ++i) {
    // The product can land an ulp past the limit; the clamp moves it less than that.
    out.tau[i] = std::clamp(scale * tau[i], -limit[i], limit[i]);
  }
  out.scale = scale;
  out.status = scale < 1.0 ? SaturationStatus::kSaturated : SaturationStatus::kWithin;
  return out;
}

}  // namespace hapticd::kinematics
