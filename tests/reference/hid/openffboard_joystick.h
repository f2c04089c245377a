// The reference OpenFFBoard as the FFB Joystick (2 Axis) that config/hid-pid-xy.yaml describes,
// for the kernel tests of hapticd against it (openffboard_xy_kernel_test.cpp) and of the board
// alone (openffboard_xy_device_kernel_test.cpp).
#pragma once

#include "openffboard.h"

namespace hapticd::reference {

// The shipped file's device: each axis 0.01 kg m^2 with its own 0.05 N m s/rad, and 2 N m at
// Magnitude 32767 (force_full_scale).
inline constexpr double kInertia = 0.01, kDamping = 0.05, kFullScale = 2.0;

// The joystick as the shipped file describes it: 40 degrees of travel (+-0.349066 rad at
// +-32767), both axes at the centre; the report rate divided by 4 as for one axis (the
// emulated USB controller cannot carry 1 kHz of input reports and the commands at once).
inline OpenFfboardOptions joystick() {
  OpenFfboardOptions o;
  o.axes = 2;
  o.degrees = 40.0;
  o.inertia = kInertia;
  o.damping = kDamping;
  o.torque_full_scale = kFullScale;
  o.start_position = 0.0;
  o.start_position_y = 0.0;
  o.usb_report_rate = 4;
  o.serial = "openffboard-xy-ref";
  return o;
}

}  // namespace hapticd::reference
