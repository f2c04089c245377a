// A reference force-feedback input device made with uinput, the kind of device hapticd's evdev
// driver meets when a program (a game controller bridge, a simulator, a firmware's user-space
// daemon) makes one: written from the kernel's uinput interface as <linux/uinput.h> documents
// it (UI_DEV_SETUP, UI_ABS_SETUP, and the force-feedback callbacks: an EV_UINPUT event with
// UI_FF_UPLOAD or UI_FF_ERASE, answered with UI_BEGIN_/UI_END_FF_UPLOAD and _ERASE) and the
// force-feedback events of Documentation/input/ff.rst (EV_FF with an effect id plays it or
// stops it; FF_GAIN and FF_AUTOCENTER set those). It shares no code with drivers/ or sim/.
//
// This process is the device: its thread runs at its own rate, integrating one axis (a mass
// with damping, pushed by the motor and by a hand) in real time and reporting the axis as
// EV_ABS with SYN_REPORT; the kernel passes a value on only when it changed, as from any
// device. The motor's force is the playing FF_CONSTANT effect: level / 0x7fff of full scale,
// times the gain, along the direction as <linux/input.h> (struct ff_effect) encodes it: "0 deg
// -> 0x0000 (down), 90 deg -> 0x4000 (left), 180 deg -> 0x8000 (up), 270 deg -> 0xC000
// (right)", so a positive level pushes toward -X at 0x4000 and +X at 0xC000: -sin(direction).
// Every upload is recorded with its time, so a test can say what reached the device each tick.
// A device can be made slow to answer uploads (upload_latency): it takes the request with
// UI_BEGIN_FF_UPLOAD at once, but takes the effect and answers with UI_END_FF_UPLOAD only that
// much later, as a device that forwards each update over a slow link of its own would; the
// kernel holds the uploading process's EVIOCSFF until then (<linux/uinput.h>: "The callback
// blocks until this return code is sent"), while the EV_FF events written meanwhile (a stop)
// still arrive.
#pragma once

#include <linux/uinput.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "unique_fd.h"

namespace hapticd::reference {

struct UinputFfOptions {
  std::string name = "hapticd reference uinput FF device";
  std::uint16_t vendor = 0x1d6b, product = 0x0104;   // what any uinput device may claim
  int axis_min = -32767, axis_max = 32767;           // ABS_X's range
  double position_min = -0.05, position_max = 0.05;  // m at the range's ends
  double full_scale = 10.0;                          // N at level 0x7fff
  double mass = 0.1, damping = 2.0, start = -0.01;   // kg, N s/m, m
  double rate_hz = 1000.0;                           // the device's own loop
  int effects = 4;                                   // ff_effects_max
  std::chrono::nanoseconds upload_latency{0};        // from UI_FF_UPLOAD to UI_END_FF_UPLOAD
};

// A playing effect stopped (EV_FF, value 0).
struct Stop {
  std::int64_t time_ns;  // CLOCK_MONOTONIC
  std::size_t uploads_before;
};

// One upload as it reached the device.
struct Upload {
  std::int64_t time_ns;  // CLOCK_MONOTONIC, when the device took it (answered it)
  int id;
  int level;
};

class UinputFfDevice {
 public:
  explicit UinputFfDevice(const UinputFfOptions& o);
  ~UinputFfDevice();  // destroyed (unplugged) if it still exists

  // /dev/input/eventN of the device.
  const std::string& event_path() const { return event_path_; }
  // A hand on the axis: a steady push (N) with its own damping (N s/m).
  void hand(double push, double damping) {
    push_.store(push);
    hand_damping_.store(damping);
  }
  double position() const;
  double force() const { return force_.load(); }  // the motor's force now
  bool playing() const { return playing_.load(); }
  int gain() const { return gain_.load(); }
  int autocenter() const { return autocenter_.load(); }
  int effects_held() const { return held_.load(); }
  std::uint64_t erases() const { return erases_.load(); }
  // Each stop of a playing effect: when it came, and how many uploads had been answered then.
  std::vector<Stop> stops() const;
  // An upload taken (UI_BEGIN_FF_UPLOAD) and not answered yet.
  bool answering() const { return answering_.load(); }
  std::vector<Upload> uploads() const;
  // The axis stops reporting (a device whose firmware hangs with its link up).
  void go_silent() { silent_.store(true); }
  // UI_DEV_DESTROY: the device is unplugged; the thread ends.
  void unplug();

 private:
  void run();
  void service();
  void upload_request(int request);
  void finish_upload();
  int poll_timeout_ms(std::chrono::steady_clock::time_point next) const;
  void erase_request(int request);
  void step(double dt);
  void emit(int type, int code, int value);

  UinputFfOptions o_;
  kernel_test::UniqueFd fd_;
  std::string event_path_;
  mutable std::mutex m_;
  double x_, v_ = 0.0;
  int reported_ = -0x7fffffff;  // the last axis value sent (none yet)
  struct Effect {
    bool used = false;
    int level = 0;
    int direction = 0;
    bool playing = false;
  };
  std::vector<Effect> effects_;
  std::vector<Upload> uploads_;
  std::vector<Stop> stops_;
  // The upload taken with UI_BEGIN_FF_UPLOAD and not answered yet (the kernel lets one at a
  // time through: ff->mutex), and when it is to be.
  std::optional<uinput_ff_upload> pending_;
  std::chrono::steady_clock::time_point pending_due_;
  std::atomic<double> push_{0.0}, hand_damping_{0.0}, force_{0.0};
  std::atomic<bool> playing_{false}, silent_{false}, stop_{false}, gone_{false};
  std::atomic<bool> answering_{false};
  std::atomic<int> gain_{0xffff}, autocenter_{-1}, held_{0};
  std::atomic<std::uint64_t> erases_{0};
  std::thread thread_;
};

}  // namespace hapticd::reference
