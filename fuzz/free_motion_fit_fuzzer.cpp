// libFuzzer target: `hapticd identify`'s fit on whatever a device could report. The input is
// a delay byte, then 8-byte (double) pairs of force and position, a tick each, a position
// whose bits are all ones standing for a tick without a fresh sample. Invariants: the fit
// throws std::invalid_argument (the data are no free device) or returns a finite, positive
// mass and damping with non-negative intervals and a residual; it never crashes or hangs.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "analysis/free_motion_fit.h"
#include "support/check.h"

using hapticd::fuzz::require;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  hapticd::analysis::FreeMotionData d;
  d.sample_period = 1e-3;
  d.delay = data[0] % 4;
  constexpr std::size_t kMaxTicks = 1024;  // the fit is O(ticks): bounded per input
  for (std::size_t at = 1; at + 16 <= size && d.force.size() < kMaxTicks; at += 16) {
    double u = 0.0, x = 0.0;
    std::memcpy(&u, data + at, 8);
    std::memcpy(&x, data + at + 8, 8);
    std::uint64_t bits = 0;
    std::memcpy(&bits, &x, 8);
    const bool fresh = bits != ~std::uint64_t{0} && std::isfinite(x);
    // The identify loop hands the fit finite numbers only: it stops on a non-finite position,
    // and its forces are its own multisine.
    d.force.push_back(std::isfinite(u) ? u : 0.0);
    d.position.push_back(fresh ? x : 0.0);
    d.valid.push_back(fresh);
  }
  try {
    const hapticd::analysis::FreeMotionFit f = hapticd::analysis::fit_free_motion(d);
    require(std::isfinite(f.mass.value) && f.mass.value > 0.0, "mass not finite and positive");
    require(std::isfinite(f.damping.value) && f.damping.value > 0.0,
            "damping not finite and positive");
    require(!(f.mass.ci95 < 0.0) && !(f.damping.ci95 < 0.0), "a negative interval");
    require(!(f.rms_residual < 0.0), "a negative residual");
    require(f.samples <= d.position.size(), "more samples fitted than given");
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
