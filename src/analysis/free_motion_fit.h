// Identification of a free device's mass m and viscous damping b (and Coulomb friction c)
// from a force it was driven with and the positions it was sampled at (`hapticd identify`).
//
// The model is the exact zero-order-hold discretisation of m dv/dt = -b v + u - c sign(v):
// with tau = m / b and a = exp(-T / tau), a force u held over period k moves the device by
//   v_{k+1} = a v_k + (1 - a) u_k / b
//   x_{k+1} = x_k + tau (1 - a) v_k + (T - tau (1 - a)) u_k / b
// (the friction term enters as the force -c sign(v_k), held like u). For a fixed tau the
// positions are linear in x_0, v_0, 1/b and c/b, so those are solved exactly by least squares
// and tau alone is searched (a grid, then golden section on log tau). That is an output-error
// fit: the encoder's quantisation is noise on the positions, not on a regressor, so it does not
// bias the estimate as an equation-error (ARX) fit on position differences would.
#pragma once

#include <cstddef>
#include <vector>

namespace hapticd::analysis {

struct FreeMotionData {
  double sample_period = 0.0;    // T (s)
  std::vector<double> force;     // u_k (N) commanded at tick k
  std::vector<double> position;  // x_k (m) read at tick k, same length
  std::vector<bool> valid;       // false: no fresh sample at tick k (left out of the fit)
  int delay = 0;                 // whole ticks between the command and the force acting
};

struct Estimate {
  double value = 0.0;
  double ci95 = 0.0;  // half-width of the 95 % confidence interval (normal approximation)
};

struct FreeMotionFit {
  Estimate mass;              // kg
  Estimate damping;           // N s/m
  Estimate coulomb;           // N; 0 with ci95 0 when the model without friction was kept
  bool coulomb_kept = false;  // friction stood clear of zero and over 0.5 % of the peak force
  double rms_residual = 0.0;  // m
  std::size_t samples = 0;    // positions fitted
  int delay = 0;
  // The device moved against the force: the data fit a negative mass and damping (mass and
  // damping above are then those of the device with the force reversed, both positive).
  bool force_reversed = false;
};

// Not RT-safe, pure. Throws std::invalid_argument for data it cannot fit (too short, sizes
// that differ, a non-positive period, no excitation) or for a result that is not a device
// (b or m not positive and finite: the data are not a free mass with damping).
FreeMotionFit fit_free_motion(const FreeMotionData& data);

// Not RT-safe, pure. The positions (from rest at 0) of the model with mass m and damping b
// driven by `force` held over each period: what `identify` expects before it moves anything.
std::vector<double> free_motion_response(const std::vector<double>& force, double mass,
                                         double damping, double sample_period);

// A multisine force: `components` sines at frequencies that are whole multiples of 1 / duration
// (so the signal is periodic over the window), log-spaced over [f_low, f_high], with
// Schroeder's phases (a low crest factor), scaled so that its largest magnitude is
// `amplitude`, faded in and out over `fade` seconds (no step when the motor starts or stops).
// Not RT-safe, pure. Throws std::invalid_argument for a band that is empty, not below Nyquist,
// or lower than one cycle over the duration.
std::vector<double> multisine(double amplitude, double f_low, double f_high, double duration,
                              double sample_period, double fade = 0.1, int components = 24);

}  // namespace hapticd::analysis
