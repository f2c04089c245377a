// The per-tick contact law of docs/math.md: penetration p = n (x - x0), the unilateral
// nonlinearity xi(p) = max(p, 0), the environment filter E(z), the virtual coupling C(z)
// through the closed-form solution of its algebraic loop, the delay line, then no_pull and
// saturation (outside the linear filters, as outside the theorems).
#pragma once

#include <cstdint>
#include <vector>

#include "control/control_law.h"

namespace hapticd::control {

// What a step did, as bits. The loop copies them into the tick record unchanged: each has the
// value of the telemetry::TickFlag of the same meaning (the loop checks that at compile time).
enum ControlFlag : std::uint32_t {
  kControlContact = 1u << 0,        // penetration > 0: the wall acts
  kControlSaturated = 1u << 1,      // |u| was limited to device.max_force
  kControlNoPullClamped = 1u << 4,  // wall.no_pull turned a pulling force into zero
  kControlUnarmed = 1u << 6,        // inside the wall before it was first left: zero force
  kControlNonFinite = 1u << 7,      // f was not finite: zero commanded, the loop faults
  // The runaway guard: deeper than law.runaway_penetration while pushing at max_force and the
  // device not slowing down (the wall is not holding): the loop commands zero and faults.
  kControlRunaway = 1u << 13,
};

struct ControlOutput {
  double penetration = 0.0;      // p = n (x - x0)
  double velocity = 0.0;         // (x_k - x_{k-1}) / T
  double force_computed = 0.0;   // f_k, wall force along n (positive pushes out of the wall)
  double force_commanded = 0.0;  // u = -n f_{k-d}, after no_pull and saturation
  std::uint32_t flags = 0;       // ControlFlag bits
};

class Controller {
 public:
  // Not RT-safe: allocates the delay line.
  explicit Controller(const ControlLaw& law);

  // RT-safe: called every tick. Never allocates, locks or throws; `position` must be finite.
  // A non-finite force (an overflow the configuration checks missed) is never commanded:
  // force_commanded is 0 and kControlNonFinite is set, for the loop to fault on.
  ControlOutput step(double position) noexcept;

  // The runaway guard's window (ticks): it compares the penetration's growth over the last
  // window with the window before. An impact the saturated wall is braking grows less each
  // window; a wall that pulls (or a hand stronger than the device) does not.
  static constexpr std::size_t kRunawayWindow = 4;

  // RT-safe. Clears every filter state and the delay line, and disarms (as at construction).
  void reset() noexcept;

  // RT-safe: called at the tick boundary where a live reload swaps this law in. Takes over the
  // signal histories (xi, f, the coupling's output), the commands already in the delay line,
  // the last position and the arming of the law it replaces, so a new K or B takes effect
  // from the next step on without a kick from the damping term or the delay line restarting.
  void continue_from(const Controller& previous) noexcept;

  const ControlLaw& law() const noexcept { return law_; }

 private:
  // The steps of step(), each RT-safe. The wall force f_k from the penetration: the coupling's
  // and the environment's histories and the unique solution of the algebraic loop; sets
  // kControlContact.
  double wall_force(double penetration, std::uint32_t& flags) noexcept;
  // f_k into the delay line; f_{k-d} out.
  double delayed(double f) noexcept;
  // The force to write from the delayed one: no_pull, finiteness (of f_k too), saturation.
  double command(double applied, double f, std::uint32_t& flags) const noexcept;
  // The runaway guard on this step's output: beyond the bound, the force at its limit pushing
  // out, and the device going in no slower than a window earlier.
  bool running_away(const ControlOutput& out) const noexcept;

  // Past values of one signal: at(i) is the value i+1 samples ago.
  class History {
   public:
    void push(double v) noexcept {
      head_ = (head_ + 1) & (kMaxTaps - 1);
      v_[head_] = v;
    }
    double at(std::size_t i) const noexcept { return v_[(head_ - i) & (kMaxTaps - 1)]; }
    void clear() noexcept { v_.fill(0.0); }

   private:
    std::array<double, kMaxTaps> v_{};
    std::size_t head_ = 0;
  };
  static_assert((kMaxTaps & (kMaxTaps - 1)) == 0, "History indexes with a mask");
  static_assert(2 * kRunawayWindow <= kMaxTaps, "the runaway guard's windows fit a History");

  ControlLaw law_;
  History xi_;               // xi(p_ve) fed to E
  History force_;            // f, E's output and C's input
  History proxy_;            // C's output
  History penetration_;      // p, for the runaway guard's two windows
  std::size_t stepped_ = 0;  // armed steps so far, up to what the windows need
  std::vector<double> delay_line_;
  std::size_t delay_head_ = 0;
  double last_position_ = 0.0;
  bool have_last_position_ = false;
  bool armed_ = false;
};

}  // namespace hapticd::control
