// A reference force-feedback joystick of two axes made with uinput: ABS_X and ABS_Y, a plant
// of its own for each (a mass with damping at the grip, pushed by the motors and by a hand the
// test sets), and FF_CONSTANT effects rendered as <linux/input.h> (struct ff_effect) encodes
// their direction: "0 deg -> 0x0000 (down), 90 deg -> 0x4000 (left), 180 deg -> 0x8000 (up),
// 270 deg -> 0xC000 (right)". Right is toward ABS_X's maximum and down toward ABS_Y's (the
// header's names of the directions, on an axis that grows down as a screen's y), so an effect
// of direction d and level L pushes the grip with L/0x7fff of full scale, times the gain, along
// (-sin d, cos d): ABS_X's motor takes the first, ABS_Y's the second. Several playing effects
// add up, as ff-memless combines them (drivers/input/ff-memless.c, ml_combine_effects: x =
// sin(d) level, y = -cos(d) level, counted toward left and up). Written from <linux/uinput.h>
// (UI_DEV_SETUP, UI_ABS_SETUP, UI_FF_UPLOAD/UI_FF_ERASE answered with UI_BEGIN_/UI_END_) as
// uinput_ff_device.h is; it shares no code with drivers/ or sim/.
//
// This process is the device: its thread integrates both axes in real time and reports each as
// EV_ABS when it changed, with one SYN_REPORT. Every upload is recorded with its time, id,
// level and direction, so a test can say what reached the device each tick. A test can make
// it fall silent, unplug it (UI_DEV_DESTROY), make ABS_Y report a value far outside its range
// from then on, or flood the node with frames of such values faster than a reader can take
// them (the kernel's buffer overflows: SYN_DROPPED) and then fall silent.
#pragma once

#include <linux/uinput.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "unique_fd.h"

namespace hapticd::reference {

struct UinputJoystickOptions {
  std::string name = "hapticd reference uinput FF joystick";
  std::uint16_t vendor = 0x1d6b, product = 0x0105;   // what any uinput device may claim
  int axis_min = -32767, axis_max = 32767;           // both axes' range
  double position_min = -0.05, position_max = 0.05;  // m at the range's ends, both axes
  double full_scale = 5.0;                           // N at level 0x7fff
  double mass = 0.1, damping = 2.0;                  // kg, N s/m, each axis
  double rate_hz = 250.0;                            // the device's own loop
  int effects = 4;                                   // ff_effects_max
};

// One upload as it reached the device.
struct JoystickUpload {
  std::int64_t time_ns;  // CLOCK_MONOTONIC, when the device answered it
  int id, level, direction;
};

class UinputFfJoystick {
 public:
  explicit UinputFfJoystick(const UinputJoystickOptions& o = {});
  ~UinputFfJoystick();  // destroyed (unplugged) if it still exists

  const std::string& event_path() const { return event_path_; }
  // A hand on the grip: a steady push (N, along x and y) with its own damping (N s/m).
  void hand(double push_x, double push_y, double damping);
  double position(int axis) const;  // m
  double force(int axis) const;     // the motors' force on the axis now, N
  bool playing() const { return playing_.load(); }
  int effects_held() const { return held_.load(); }
  std::vector<JoystickUpload> uploads() const;
  std::size_t stops() const;  // playing effects stopped (EV_FF value 0)
  // The axes stop reporting (a firmware that hangs with its link up).
  void go_silent() { silent_.store(true); }
  // ABS_Y reports `value` from now on, whatever the grip does (a corrupted axis: the kernel
  // passes a value on only when it changes, so it stands). The input core neither clamps nor
  // checks it (<linux/input.h>, struct input_absinfo).
  void corrupt_y(int value) { jump_.store(value); }
  // `frames` frames of both axes at values up to `scale` times the range's end, written at
  // once (more than the kernel's buffer for a reader holds: it drops them and says
  // SYN_DROPPED), and then nothing more: the last frame's values stand.
  void flood(int frames, int scale) {
    flood_scale_.store(scale);
    flood_.store(frames);
  }
  // UI_DEV_DESTROY: the device is unplugged; the thread ends.
  void unplug();

 private:
  struct Effect {
    bool used = false, playing = false;
    int level = 0, direction = 0;
  };
  void run();
  void service();
  void upload_request(int request);
  void erase_request(int request);
  void step(double dt);
  void report();
  void corrupt();
  void write_events(const input_event* ev, std::size_t n);
  int value_of(double x) const;

  UinputJoystickOptions o_;
  kernel_test::UniqueFd fd_;
  std::string event_path_;
  mutable std::mutex m_;
  std::array<double, 2> x_{}, v_{}, push_{}, force_{};
  double hand_damping_ = 0.0;
  std::array<int, 2> reported_{-0x7fffffff, -0x7fffffff};  // the last values sent
  std::vector<Effect> effects_;
  std::vector<JoystickUpload> uploads_;
  std::size_t stops_ = 0;
  std::atomic<bool> playing_{false}, silent_{false}, stop_{false}, gone_{false};
  std::atomic<int> held_{0}, jump_{0x7fffffff}, flood_{0}, flood_scale_{1};
  int stuck_y_ = 0x7fffffff;  // the value ABS_Y reports from corrupt_y on
  std::thread thread_;
};

}  // namespace hapticd::reference
