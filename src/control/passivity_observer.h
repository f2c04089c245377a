// The runtime passivity observer and controller of Hannaford and Ryu ("Time-domain passivity
// control of haptic interfaces", IEEE Transactions on Robotics and Automation, 2002), made
// exact for the sampled-data loop the startup gate analyses.
//
// Sign convention: energy flowing INTO the rendered wall from the device is positive, so a
// passive wall keeps its observed energy >= 0 (it only hands back what it was given). Over a
// sample period the motor force u (device frame) is held by the ZOH, so the work it does on
// the device is exactly u (x_{k+1} - x_k), whatever the motion inside the period: no velocity
// estimate is involved. The force acting over a period is the one written the driver's
// declared transport delay earlier (whole ticks).
//
// A sampled wall alone is never passive (the ZOH's half-sample lag makes it active); what the
// gate proves is that the device's physical damping b absorbs that excess (Colgate's bound as
// sharpened by Roberts, Moore and Colgate, "The effect of device dynamics on the passivity of
// sampled-data haptic systems"). Their proof credits b with what it must dissipate over a
// period in which the device moved dx: at least b dx^2 / T (Cauchy-Schwarz on the integral of
// v^2). The observer credits exactly that, so the sum it keeps,
//   E_k = sum over periods of ( b dx^2 / T  -  u dx ),
// is what the gate's theorem says stays >= 0 for every motion when the gate passes, and a
// negative E_k is energy the sampled loop put into the hand that b cannot have taken out.
// Across stale ticks and skipped periods the motion is spread evenly over the periods it
// spans (the credit b dx^2 / (n T), the work with the mean of the forces that acted; over
// skipped periods, where nothing was written, the one acting at the last tick).
//
// The controller (safety.passivity_controller: damp): while E_k < 0 it adds the damping
// alpha = -E_k / (v^2 T) (v = dx / (n T) of the last sample) that would dissipate the deficit
// over the next period, as a force -alpha v' on top of the wall's command (saturated again to
// device.max_force; under wall.no_pull never pulling). The force is held over the NEXT period,
// where the velocity is not known yet: v' is v, or -v when the last period reversed the
// motion (a damper on the last velocity feeds the Nyquist-rate bounce a failing sampled wall
// falls into, measured on the coupling paper's example). A wrong guess makes that force push
// along the motion, so a governor watches the controller's own work, which the observer
// measures like the wall's: within one deficit (E_k < 0 from when it went negative) the
// controller acts only while its forces have taken out at least what they put in, and stops
// for the rest of the deficit once they have not. alpha is also bounded by
// safety.passivity_max_damping and by 0.9 * 2m/T: a damper held over a period changes a free
// mass's velocity by the factor 1 - alpha T/m, which overshoots (reverses it) above m/T and
// grows it above 2m/T.
#pragma once

#include <cstdint>
#include <vector>

#include "config/config.h"
#include "control/control_law.h"

namespace hapticd::control {

struct ObserverParams {
  config::PassivityControl mode = config::PassivityControl::kObserve;
  double device_damping = 0.0;  // b credited (N s/m)
  double sample_period = 0.0;   // T (s)
  int device_delay = 0;         // whole ticks between write() and the force acting
  double max_damping = 0.0;     // the controller's bound on alpha (N s/m)
};

// The fraction of 2m/T the controller's damping stays below.
inline constexpr double kStableDampingFraction = 0.9;

// "off", "observe", "damp": the value of safety.passivity_controller.
const char* passivity_mode_name(config::PassivityControl mode) noexcept;

// Not RT-safe, pure. From the configuration and the driver's declared delay; max_damping is
// safety.passivity_max_damping or 0.9 * 2m/T, whichever is smaller.
ObserverParams observer_params(const config::Config& cfg, int device_delay_samples);

// What one observation and the controller did.
struct Damping {
  double command = 0.0;    // the force to write: the wall's plus the controller's, saturated
  double added = 0.0;      // command minus the wall's: the controller's part of it
  double alpha = 0.0;      // damping the controller added this tick (N s/m), 0: none
  bool saturated = false;  // the sum had to be limited to max_force
};

class PassivityObserver {
 public:
  // Not RT-safe: sizes the command history for the delay. Throws std::invalid_argument for a
  // negative delay or a non-positive period.
  explicit PassivityObserver(const ObserverParams& params);

  // RT-safe: called every tick that has a position (the held one on a stale tick), before
  // the command is written. `fresh`: a new sample; `periods`: sample periods since the
  // previous tick (1; more after the loop skipped periods). Accounts the period(s) just ended.
  void observe(double position, bool fresh, std::uint32_t periods) noexcept;

  // RT-safe: called every tick that has a position, after observe(). The command to write:
  // `wall` (the controller's, already saturated) plus, in damp mode while the energy is
  // negative, the controller's damping force; the sum saturated to the law's max_force and,
  // under its no_pull, never pulling (the law in force: a live reload may change them).
  Damping damp(double wall, const ControlLaw& law) noexcept;

  // RT-safe: called every tick with the force really written (0 when none was) and the
  // controller's part of it (Damping::added, 0 when the wall's alone was written): the
  // history the work of later periods is computed from.
  void commanded(double force, double added) noexcept;

  // RT-safe. A new run (after a cleared fault): no previous position, no force in flight.
  // The energies go on accumulating.
  void restart() noexcept;
  // RT-safe: a swap at a tick boundary (a reload of a scene's walls). Goes on from `previous`
  // - its energies, its last position, the forces in flight - with its own parameters (the
  // damping the gate credits the new wall with).
  void continue_from(const PassivityObserver& previous) noexcept;

  bool enabled() const noexcept { return params_.mode != config::PassivityControl::kOff; }
  // E_k (J): energy into the wall and the device's damping, positive while passive.
  double energy_j() const noexcept { return energy_; }
  // The work the commanded force did on the device, sum of u dx (J).
  double wall_work_j() const noexcept { return wall_work_; }
  double min_energy_j() const noexcept { return min_energy_; }
  std::uint64_t negative_ticks() const noexcept { return negative_ticks_; }
  std::uint64_t damped_ticks() const noexcept { return damped_ticks_; }
  double max_alpha() const noexcept { return max_alpha_; }
  // Energy the controller's force took out of the device (J), sum of -(-alpha v) dx.
  double damping_work_j() const noexcept { return damping_work_; }

 private:
  // The slot of the command that acted over the period just ended.
  std::size_t acting() const noexcept;

  ObserverParams params_;
  double inv_period_ = 0.0;
  std::vector<double> history_;          // commands, newest at head_; a power-of-two size
  std::vector<double> damping_history_;  // their damping part
  std::size_t mask_ = 0;
  std::size_t head_ = 0;
  double last_x_ = 0.0;
  bool have_x_ = false;
  double pending_force_ = 0.0;    // sum over pending periods of the acting force
  double pending_damping_ = 0.0;  // of the controller's part of it
  std::uint32_t pending_periods_ = 0;
  double velocity_ = 0.0;           // of the last fresh sample
  double previous_velocity_ = 0.0;  // of the one before
  double energy_ = 0.0;
  double wall_work_ = 0.0;
  double damping_work_ = 0.0;
  double min_energy_ = 0.0;
  std::uint64_t negative_ticks_ = 0;
  std::uint64_t damped_ticks_ = 0;
  double max_alpha_ = 0.0;
  bool in_deficit_ = false;          // E < 0 since it last went negative
  double deficit_start_work_ = 0.0;  // damping_work_ when it did
};

}  // namespace hapticd::control
