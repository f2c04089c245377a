// The direction check (docs/devices.md; its fit in docs/math.md): after output is enabled and
// before the wall is armed, which way a positive command really pushes the device. No gate can
// see a reversed force: the passivity bound and the observer both assume its sign, and a
// reversed wall pulls the device in until it saturates.
//
// Once the device is at rest (its positions over the last 2n ticks spread less than a quarter
// of the motion the pulse will cause), the probe commands a doublet: n ticks of F, then n of
// -F exp(-n T b / m) (a push out of the wall, then the brake that stops the model's device
// again), then n + d ticks of zero (d: the driver's declared delay). The positions over the
// rest window and the push (up to where the brake begins to act) are fitted by least squares to
//   y_i = a + c i + g e_i,
// e the response the configured mass and damping predict for the same force from rest (the
// exact ZOH model, analysis::free_motion_response), a + c i whatever drift the device had. Only
// the push is fitted: from rest, a mass held by any spring and damper first moves the way it is
// pushed, while what follows depends on the hand. The gain g says which way and how much: about
// 1 for a free device pushed as commanded, less for a hand holding it, negative for a reversed
// force (the fit of a negative mass); a |g| under safety.direction_check.min_motion, or within
// four standard errors of zero, is no motion.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "config/config.h"

namespace hapticd::control {

enum class ProbeState : std::uint8_t {
  kOff,          // safety.direction_check.mode: off
  kWaiting,      // zero force, waiting for the device to be at rest
  kPulsing,      // the pulse and the motion after it
  kConfirmed,    // the device moved the way the force pushed
  kReversed,     // it moved the other way: a wall would pull
  kNoMotion,     // it did not move measurably (held firmly, or too heavy for the pulse)
  kNeverAtRest,  // it did not come to rest within rest_timeout_ms
};

// "off", "waiting", "pulsing", "confirmed", "reversed", "no motion", "never at rest".
const char* probe_state_name(ProbeState s) noexcept;
// Whether the check has ended (any state but waiting and pulsing).
inline bool probe_ended(ProbeState s) noexcept {
  return s != ProbeState::kWaiting && s != ProbeState::kPulsing;
}

// What the probe does, resolved from the configuration once, off the RT thread.
struct ProbePlan {
  bool enabled = false;
  double force = 0.0;  // the first half's force (N), signed: along -wall.normal
  // The second half's force as a share of -force: exp(-n T b / m), what stops the model's
  // device exactly (its damping has already taken that much of the speed the push gave it).
  double brake = 1.0;
  int half_ticks = 3;                   // n
  int rest_ticks = 6;                   // R = 2n: the rest window, the fit's baseline
  int delay = 0;                        // d: the driver's declared transport delay
  std::uint64_t max_wait_ticks = 1000;  // ticks with a position before giving up on rest
  double rest_tolerance = 0.0;          // the largest spread of positions at rest (m)
  double min_gain = 0.2;
  double expected_peak = 0.0;            // the model's largest displacement (m), signed
  std::vector<double> expected;          // e_i over the window: R zeros, then 3n + d
  std::size_t fitted = 0;                // the first R + n + d of them: the rest and the push
  std::array<double, 9> gram_inverse{};  // of [1, i, e_i] over the fitted part, row-major
  std::size_t window() const noexcept { return expected.size(); }
  // RT-safe. The force of pulse tick j (0 from 2n on).
  double force_at(int j) const noexcept;
};

// Not RT-safe, pure. The plan for `cfg` with the driver's declared delay. Throws
// std::invalid_argument when the model predicts no motion at all (it cannot: m, b > 0).
ProbePlan probe_plan(const config::Config& cfg, int device_delay);

struct ProbeResult {
  ProbeState state = ProbeState::kOff;
  double gain = 0.0;           // g: the motion over the model's, signed
  double gain_error = 0.0;     // its standard error
  double force = 0.0;          // the first half's force (N)
  double expected_peak = 0.0;  // the model's largest displacement (m)
  std::uint64_t ticks = 0;     // ticks the check took (waiting and pulsing)
};

class DirectionProbe {
 public:
  // Not RT-safe: holds the plan and sizes the windows.
  explicit DirectionProbe(ProbePlan plan);

  // RT-safe. From the start: waiting for rest (or off).
  void restart() noexcept;
  // RT-safe: called every tick with a position until ended(). The force to write this tick.
  // `periods`: sample periods since the previous tick; a pulse that more than one passed
  // (the loop skipped periods) no longer matches the model, and waits for rest again.
  double step(double position, std::uint32_t periods = 1) noexcept;
  bool ended() const noexcept { return probe_ended(result_.state); }
  const ProbeResult& result() const noexcept { return result_; }
  const ProbePlan& plan() const noexcept { return plan_; }

 private:
  double wait(double position) noexcept;
  void decide() noexcept;

  ProbePlan plan_;
  std::vector<double> rest_;    // ring of the last R positions
  std::vector<double> window_;  // the rest window, then the positions after the pulse began
  std::size_t rest_head_ = 0;
  std::size_t rest_count_ = 0;
  int pulse_tick_ = 0;
  ProbeResult result_;
};

}  // namespace hapticd::control
