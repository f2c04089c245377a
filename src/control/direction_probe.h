// The direction check (docs/devices.md; its fit in docs/math.md): after output is enabled and
// before the wall is armed, which way a positive command really pushes the device. No gate can
// see a reversed force: the passivity bound and the observer both assume its sign, and a
// reversed wall pulls the device in until it saturates.
//
// Once the device is at rest (its positions over the last 2n ticks spread less than a quarter
// of the motion the pulse will cause), the probe pushes with F for n ticks, out of the wall,
// then watches with zero force for as long as its response may take to come (D: the driver's
// declared delay d and up to max_latency_ms more). The positions over the rest window and the
// push's own response are fitted by least squares to
//   y_i = a + c i + g e_i,
// e the response the configured mass and damping predict for the same force from rest (the
// exact ZOH model, analysis::free_motion_response), a + c i whatever drift the device had. The
// gain g says which way and how much: about 1 for a free device pushed as commanded, less for a
// hand holding it, negative for a reversed force (the fit of a negative mass); a |g| under
// safety.direction_check.min_motion, or within four standard errors of zero, is no motion.
// The push is one-sided: whatever a slow link drops or delays of it, what reaches the device
// never pushes the other way. From rest, a mass held by any spring and damper first moves the
// way it is pushed; only later may a hand's spring pull it back. So the delay is searched from
// the declared one up, and the first fit with significant motion fixes the sign (a delay
// shorter than the device's own still sees the start of the push's response; a longer one
// could see the hand's); the best fit of that sign gives the latency. A device that moves far
// more than the push could move it (|g| over 4) was being moved by something else: the check
// waits for rest and tries again, until rest_timeout_ms. Once confirmed, and only
// then, a brake of n ticks takes out what speed the model's device would still have (a
// reversed force would turn a brake into a push).
//
// The loop may skip periods (an overrun: the host stalled it). The device kept the command it
// had over them, so the pulse is followed in periods, not ticks: the skipped periods' positions
// are missing rows of the fit, and a push held past its end by a skip is a longer push, whose
// response and brake the model gives as well (the ZOH response is linear in the force). Only a
// push held past twice its length, or a fit left with too few rows, is given up for a new one.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "config/config.h"

namespace hapticd::control {

enum class ProbeState : std::uint8_t {
  kOff,          // safety.direction_check.mode: off
  kWaiting,      // zero force, waiting for the device to be at rest
  kPulsing,      // the push and the motion after it
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
  double force = 0.0;  // the push's force (N), signed: along -wall.normal
  // The brake's force as a share of -force, after a confirmed push of n periods decided n + D
  // after it began: exp(-(n + D) T b / m), what stops the model's device exactly (its damping
  // has taken that much of the speed the push gave it by the time the brake ends).
  double brake = 1.0;
  double decay = 0.0;                   // T b / m: the model's speed decays by exp(-decay) a period
  int half_ticks = 3;                   // n
  int rest_ticks = 6;                   // R = 2n: the rest window, the fit's baseline
  int delay = 0;                        // d: the driver's declared transport delay
  std::uint64_t max_wait_ticks = 1000;  // ticks with a position before giving up on rest
  double rest_tolerance = 0.0;          // the largest spread of positions at rest (m)
  // The quadratic term of a least-squares fit of the rest window is sum w_i y_i (oldest
  // first); at rest, extrapolated over the push's horizon (n + D), it moves the device less
  // than curvature_tolerance: a hand accelerating it would be read as the push's motion.
  std::vector<double> curvature_weights;
  double curvature_tolerance = 0.0;  // (m)
  double min_gain = 0.2;
  int max_delay = 0;           // D: d and the latency allowed beyond it (ticks)
  double expected_peak = 0.0;  // the model's largest displacement (m), signed
  // The model's positions j periods after `force` began to be held, and on: n + D + 1 of them.
  std::vector<double> step_response;
  // The positions recorded: the rest window (R), then n + D after the push began.
  std::size_t window() const noexcept {
    return static_cast<std::size_t>(rest_ticks + half_ticks + max_delay);
  }
  // RT-safe. e_c(i): the model's position at window index i for a response c periods late to
  // a push of `push` periods.
  double expected(int c, std::size_t i, int push) const noexcept;
  // RT-safe. The brake's share of -force that stops the model's device after a push of `push`
  // periods, the brake beginning `start` periods after the push began (brake, for n and n + D).
  double brake_after(int push, int start) const noexcept;
  // RT-safe. The force of the pulse's period j: the push's n, then zero.
  double force_at(int j) const noexcept { return j < half_ticks ? force : 0.0; }
};

// Not RT-safe, pure. The plan for `cfg` with the driver's declared delay. Throws
// std::invalid_argument when the model predicts no motion at all (it cannot: m, b > 0).
ProbePlan probe_plan(const config::Config& cfg, int device_delay);

struct ProbeResult {
  ProbeState state = ProbeState::kOff;
  double gain = 0.0;           // g: the motion over the model's, signed
  double gain_error = 0.0;     // its standard error
  double force = 0.0;          // the push's force (N)
  double expected_peak = 0.0;  // the model's largest displacement (m)
  std::uint64_t ticks = 0;     // ticks the check took (waiting and pulsing)
  int latency = 0;             // ticks the best fit's response came after the declared delay
};

class DirectionProbe {
 public:
  // Not RT-safe: holds the plan and sizes the windows.
  explicit DirectionProbe(ProbePlan plan);

  // RT-safe. From the start: waiting for rest (or off).
  void restart() noexcept;
  // RT-safe: called every tick with a position until ended(). The force to write this tick.
  // `periods`: sample periods since the previous tick (more than one when the loop skipped
  // some, over which the device held the last force).
  double step(double position, std::uint32_t periods = 1) noexcept;
  // Whether it commands nothing more: a verdict reached, and a confirmed one's brake done.
  bool ended() const noexcept { return probe_ended(result_.state) && braking_ == 0; }
  const ProbeResult& result() const noexcept { return result_; }
  const ProbePlan& plan() const noexcept { return plan_; }

 private:
  bool at_rest() const noexcept;
  double wait(double position) noexcept;
  // RT-safe. The pulse's next position, `periods` after the last; the force to write.
  double pulse(double position, std::uint32_t periods) noexcept;
  // RT-safe. The pulse given up (held too long, or too few positions): wait for rest again.
  double start_over() noexcept;
  void decide() noexcept;
  // The fit for a response c ticks late: {g, its standard error}.
  std::array<double, 2> fit(int c) const noexcept;

  ProbePlan plan_;
  std::vector<double> rest_;    // ring of the last R positions
  std::vector<double> window_;  // the rest window, then the positions after the pulse began
  // The window's positions less the rest window's own line (its drift carried on).
  std::vector<double> residual_;
  std::vector<std::uint8_t> present_;  // 1 for each window index a position was read at
  std::size_t rest_head_ = 0;
  std::size_t rest_count_ = 0;
  int pulse_period_ = 0;  // periods since the pulse began
  int push_ = 0;          // periods the push was held: n, or more after a skip at its end
  int braking_ = 0;       // brake periods left after a confirmed push
  double brake_ = 0.0;    // the brake's share of -force for this push
  ProbeResult result_;
};

}  // namespace hapticd::control
