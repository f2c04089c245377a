#include "logitech_wheel.h"
#include "reference_clock.h"

#include <time.h>

#include <algorithm>
#include <cmath>

namespace hapticd::reference {
namespace {

constexpr int kXMax = 16383;  // 14 bits

}  // namespace

std::vector<std::uint8_t> logitech_wheel_descriptor() {
  return {
      0x05, 0x01,        // Usage Page: Generic Desktop
      0x09, 0x04,        // Usage: Joystick
      0xA1, 0x01,        // Collection: Application
      0xA1, 0x02,        //   Collection: Logical (the wheel's input)
      0x95, 0x01,        //     Report Count 1
      0x75, 0x0E,        //     Report Size 14
      0x14,              //     Logical Minimum 0
      0x26, 0xFF, 0x3F,  //     Logical Maximum 16383
      0x34,              //     Physical Minimum 0
      0x46, 0xFF, 0x3F,  //     Physical Maximum 16383
      0x09, 0x30,        //     Usage: X (the wheel)
      0x81, 0x02,        //     Input: Data, Variable, Absolute
      0x95, 0x0E,        //     Report Count 14
      0x75, 0x01,        //     Report Size 1
      0x25, 0x01,        //     Logical Maximum 1
      0x45, 0x01,        //     Physical Maximum 1
      0x05, 0x09,        //     Usage Page: Button
      0x19, 0x01,        //     Usage Minimum 1
      0x29, 0x0E,        //     Usage Maximum 14
      0x81, 0x02,        //     Input: Data, Variable, Absolute
      0x05, 0x01,        //     Usage Page: Generic Desktop
      0x95, 0x01,        //     Report Count 1
      0x75, 0x04,        //     Report Size 4
      0x25, 0x07,        //     Logical Maximum 7
      0x46, 0x3B, 0x01,  //     Physical Maximum 315
      0x65, 0x14,        //     Unit: degrees
      0x09, 0x39,        //     Usage: Hat Switch
      0x81, 0x42,        //     Input: Data, Variable, Null State
      0x65, 0x00,        //     Unit: none
      0x26, 0xFF, 0x00,  //     Logical Maximum 255
      0x46, 0xFF, 0x00,  //     Physical Maximum 255
      0x75, 0x08,        //     Report Size 8
      0x81, 0x01,        //     Input: Constant
      0x09, 0x31,        //     Usage: Y (throttle)
      0x81, 0x02,        //     Input: Data, Variable, Absolute
      0x09, 0x35,        //     Usage: Rz (brake)
      0x81, 0x02,        //     Input: Data, Variable, Absolute
      0x81, 0x01,        //     Input: Constant
      0xC0,              //   End Collection
      0xA1, 0x02,        //   Collection: Logical (the force commands)
      0x09, 0x02,        //     Usage 2
      0x95, 0x07,        //     Report Count 7 (of 8 bits, 0..255)
      0x91, 0x02,        //     Output: Data, Variable, Absolute
      0xC0,              //   End Collection
      0xC0,              // End Collection
  };
}

LogitechWheel::LogitechWheel(const LogitechWheelOptions& o)
    : o_(o),
      axis_(o.inertia, o.damping, o.start_position),
      usb_({kVendor, kProduct, 0x0100, "Logitech", "Logitech WingMan Formula Force GP", o.serial},
           logitech_wheel_descriptor(),
           {[this](std::span<const std::uint8_t> r) { output(r); },
            [](std::span<const std::uint8_t>) { return false; },
            [](std::uint8_t) { return std::optional<std::vector<std::uint8_t>>{}; }},
           false),
      loop_([this] { loop(); }) {}

LogitechWheel::~LogitechWheel() {
  stop_.store(true);
  loop_.join();
  usb_.unplug();
}

std::vector<WheelCommand> LogitechWheel::commands() const {
  const std::lock_guard lock(m_);
  return commands_;
}

// The constant force as either Logitech driver writes it: hid-lgff 0x51 0x08 X Y (0x7f the
// centre), hid-lg4ff 0x11 0x08 X 0x80 into force slot 1 (0x80 the centre) and 0x13 0x00 to
// switch that slot off. X above the centre turns the wheel left, toward -X (the header says
// whose word that is).
void LogitechWheel::output(std::span<const std::uint8_t> r) {
  {
    const std::lock_guard lock(m_);
    commands_.push_back({now_ns(), {r.begin(), r.end()}});
  }
  if (r.size() < 3) return;
  if (r[0] == 0x51 && r[1] == 0x08) {
    torque_.store(-(static_cast<double>(r[2]) - 0x7f) / 127.0 * o_.torque_full_scale);
  } else if (r[0] == 0x11 && r[1] == 0x08) {
    torque_.store(-(static_cast<double>(r[2]) - 0x80) / 127.0 * o_.torque_full_scale);
  } else if (r[0] == 0x13) {
    torque_.store(0.0);
  }
}

// The wheel's own loop: the axis turns under the torque it holds; a report goes out when the
// 14-bit count changed, at most every 2 ms, and the unchanged one again after 100 ms (the HID
// idle rate, HID 1.11 7.2.4), so a host that opens the wheel late still learns where it is.
void LogitechWheel::loop() {
  const double half_range = o_.degrees / 2.0 * M_PI / 180.0;
  std::int64_t last = now_ns(), last_sent = 0;
  int sent = -1;
  while (!stop_.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const std::int64_t now = now_ns();
    axis_.step(std::min(0.01, (now - last) * 1e-9), torque_.load());
    last = now;
    const double x = std::clamp(axis_.position(), -half_range, half_range);
    const int count = static_cast<int>(std::lround((x + half_range) / (2 * half_range) * kXMax));
    if ((count == sent && now - last_sent < 100'000'000) || !usb_.configured()) continue;
    // X in the low 14 bits, no button, the hat's null state (8), pedals released (0xFF).
    const std::uint8_t report[8] = {static_cast<std::uint8_t>(count & 0xFF),
                                    static_cast<std::uint8_t>((count >> 8) & 0x3F),
                                    0,
                                    0x80,
                                    0,
                                    0xFF,
                                    0xFF,
                                    0};
    if (usb_.send_input(report)) {
      sent = count;
      last_sent = now;
    }
  }
}

}  // namespace hapticd::reference
