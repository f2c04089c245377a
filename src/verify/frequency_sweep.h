// The search over frequencies `hapticd verify` makes, whatever loop it measures: the damping
// below which the device hands net energy to an operator imposing x = A cos(theta k) is
// measured at theta = 2 pi p / q (whole periods only, memoised), and worst_damping finds its
// largest value up to Nyquist. The one-joint sweep (passivity_sweep.cpp) and the sweep along a
// wall's normal at several joints (workspace_verify.cpp) each say how one frequency is measured.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "verify/passivity_sweep.h"

namespace hapticd::verify {

class FrequencySweep {
 public:
  virtual ~FrequencySweep() = default;

  // The measured damping at theta = 2 pi p / q (rad per sample).
  double damping_zero(std::int64_t p, std::int64_t q);

  std::uint64_t ticks() const { return ticks_; }
  const std::vector<SweepPoint>& points() const { return sweep_; }

 protected:
  // `nyquist_pole`: the loop resonates at Nyquist (Tustin), so an odd period's window is
  // doubled to average a Nyquist-rate transient out.
  FrequencySweep(double sample_period_s, bool nyquist_pole)
      : period_s_(sample_period_s), nyquist_pole_(nyquist_pole) {}
  // The damping measured at `theta` over `window` ticks, whole multiples of `period` ticks;
  // adds the ticks it simulated to ticks_.
  virtual double measure(double theta, std::int64_t period, std::int64_t window) = 0;

  std::uint64_t ticks_ = 0;

 private:
  double period_s_;
  bool nyquist_pole_;
  std::map<std::pair<std::int64_t, std::int64_t>, double> memo_;
  std::vector<SweepPoint> sweep_;
};

// Ticks before a measurement window for the filters' start-up transient to decay: short for a
// bare wall (E is FIR for backward); behind a coupling with a pole at z = 1, until H's slowest
// pole (`slowest_pole`, its spectral radius) has decayed by 1e-6 (13.8 time constants). Its
// transient would otherwise be measured as power at the lowest frequencies; what is left of it
// is nearly constant over a window of whole periods and averages out: measured on couplings
// with poles up to 1 - 3e-5, it moved the measured b_req by at most 1e-2 of its remaining
// fraction, so here by 1e-8 of b_req against the tolerance of 1e-3 (at 1e-12, 27.6 time
// constants, twice the ticks, the same verdicts to 1e-6).
std::int64_t warmup_ticks(int total_delay, double slowest_pole);

// The largest measured damping zero over the frequencies up to Nyquist: a coarse grid
// theta = pi j / J (Tustin's pole at -1 resonates exactly at Nyquist, left out), low
// frequencies where delayed walls peak as theta -> 0, then a ternary search around the coarse
// maximum on the finer grid theta = 2 pi p / Q.
double worst_damping(FrequencySweep& sweep, bool tustin);

// The sweep's points sorted by frequency, and the frequency of the largest (`best`).
double worst_frequency_hz(std::vector<SweepPoint>& points, double best);

}  // namespace hapticd::verify
