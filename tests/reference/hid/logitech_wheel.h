// A reference Logitech force-feedback wheel as a USB device on the raw gadget (raw_usb_hid.h),
// for the kernel's own Logitech driver: written from the kernel's published sources, not from
// hapticd's codecs.
//   - identity: the WingMan Formula Force GP, USB 046d:c293, which hid-lg's device table
//     (drivers/hid/hid-lg.c, lg_devices) gives to one of its force-feedback drivers, both on
//     ff-memless: hid-lgff (LG_FF, in the older tables) or hid-lg4ff (Linux 6.1 binds that one:
//     "Force feedback support for Logitech Gaming Wheels");
//   - report descriptor: the layout of the Logitech wheels hid-lg publishes for the Driving
//     Force Pro (dfp_rdesc_fixed): a 14-bit X (the wheel), 14 buttons, a hat, Y and Rz pedals,
//     and one 7-byte output report, which hid-lgff requires (lgff_init validates field 0 of the
//     first output report for 7 values);
//   - force: the memless core combines the effects into one signed 8-bit force per axis, and
//     hid_lgff_play writes 0x51 0x08 X Y (X offset by 0x7f, "0x7f is center"), lg4ff_play
//     0x11 0x08 X 0x80 into force slot 1 (offset by 0x80, "0x80 is no force") or 0x13 0x00 to
//     switch the slot off; the wheel turns with (X - centre) / 127 of its full torque, a byte
//     above the centre to the left, toward -X (its X grows to the right). Logitech's classic
//     format as its users write it: nightmode/logitech-g29 (3159ce8c, code/index.js
//     forceConstant sends round(|n - 1| * 255), docs/api.md: "forceConstant(0) // full left",
//     "(1) // full right"; data-map.js: wheel turn "0 is far left, 255 is far right") and
//     wiibrew.org's "Logitech USB steering wheel" ("0x00 is to right, 0x80 is zero force, 0xFF
//     is to left"). That is the kernel's documented direction through ff-memless: 0x4000 is
//     "left" (<linux/input.h>) and ml_combine_effects makes X = sin(direction) * level, above
//     the centre for a positive level. hid-lgff's 0x51 byte is taken the same way: only the
//     kernel's documentation speaks for it.
// The wheel reports its axis on change, every 2 ms at most, and again after 100 ms without a
// change; every output report is recorded
// with its time, so a test can say what hapticd's force became on the wire.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "axis_plant.h"
#include "raw_usb_hid.h"

namespace hapticd::reference {

struct LogitechWheelOptions {
  std::string serial = "lg-ffgp-ref";
  double degrees = 270.0;        // lock to lock: X spans it over 0..16383
  double torque_full_scale = 2;  // N m (toward -X) at X = centre + 127
  double inertia = 0.05, damping = 0.05, start_position = -0.1;  // kg m^2, N m s/rad, rad
};

// One output report as it reached the wheel.
struct WheelCommand {
  std::int64_t time_ns;  // CLOCK_MONOTONIC
  std::vector<std::uint8_t> bytes;
};

class LogitechWheel {
 public:
  static constexpr std::uint16_t kVendor = 0x046d, kProduct = 0xc293;

  explicit LogitechWheel(const LogitechWheelOptions& o);
  ~LogitechWheel();  // unplugged

  AxisPlant& axis() { return axis_; }
  double torque() const { return torque_.load(); }
  std::vector<WheelCommand> commands() const;
  std::string error() const { return usb_.error(); }

 private:
  void output(std::span<const std::uint8_t> r);
  void loop();

  LogitechWheelOptions o_;
  AxisPlant axis_;
  std::atomic<double> torque_{0.0};
  mutable std::mutex m_;
  std::vector<WheelCommand> commands_;
  std::atomic<bool> stop_{false};
  RawUsbHid usb_;
  std::thread loop_;
};

// The wheel's report descriptor (above).
std::vector<std::uint8_t> logitech_wheel_descriptor();

}  // namespace hapticd::reference
