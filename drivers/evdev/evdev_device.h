// The evdev driver's Device: the lifecycle over an EvdevTransport (libevdev on
// /dev/input/eventN, or the loopback socketpair), one axis or two (device.evdev.axes: a
// joystick's ABS_X and ABS_Y, one FF_CONSTANT whose direction and level follow the force, or one
// per axis). configure uploads the FF_CONSTANT effect(s) at level 0 and sets FF_GAIN and
// FF_AUTOCENTER as configured; enable grabs the device
// (EVIOCGRAB), turns autocenter off and plays the effect; every tick drains the events and
// updates the effect's level (EVIOCSFF); disable and every fault set level 0, stop and erase
// the effect, give autocenter back and release the grab. The updates go through the update
// thread (update_thread.h): EVIOCSFF waits for the device, the RT thread never does. The input
// core passes an axis value only when it changes, so a tick without one holds the last
// position; no event for device.evdev.liveness_ms while a force is commanded is stale data. An
// unplugged device is a transport fault, and so are an update the kernel refused and updates
// slower than the declared delay covers; the device stopping the effect itself (EV_FF_STATUS)
// is a device fault.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>

#include "drivers/device.h"
#include "drivers/evdev/device_select.h"
#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_transport.h"
#include "drivers/evdev/update_thread.h"
#include "drivers/io/counter_unwrap.h"

namespace hapticd::drivers::evdev {

class EvdevDevice final : public Device {
 public:
  // What `open` found: the transport, and the listing of the device where it has one (the
  // loopback has none), for the notices about its kernel driver.
  struct Opened {
    std::unique_ptr<EvdevTransport> transport;
    std::optional<InputListing> listing;
  };
  // Not RT-safe. `open` opens the transport (called by configure, again after a close).
  // `realtime`: the loop keeps time (loop.clock realtime), so an update longer than the
  // declared delay covers is late; in freerun nothing waits on the clock and none is (each is
  // still timed and the longest counted).
  EvdevDevice(std::shared_ptr<const EvdevSettings> settings, std::function<Opened()> open,
              double sample_period_s, bool realtime = true);
  ~EvdevDevice() override;

  std::string_view driver_name() const noexcept override { return "evdev"; }
  void emergency_stop() noexcept override;
  std::vector<std::string> notices() const override { return notices_; }
  std::span<const base::Counter> counters() const noexcept override { return c_; }
  // RT-safe: waits until the newest level written has been through EVIOCSFF (the loopback's
  // pacing).
  void wait_output() const noexcept override;

 protected:
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_close() noexcept override;
  IoStatus on_read(std::span<PositionSample> samples) noexcept override;
  IoStatus on_write(std::span<const double> forces) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  static constexpr int kMaxDrain = 512;  // events per tick: a flooding device cannot stall it
  // Fault codes beyond errno: the device stopped the effect itself (EV_FF_STATUS); updates
  // took longer than the declared delay covers, late_update_fault of them in a row.
  static constexpr std::uint32_t kEffectStopped = 0x10000;
  static constexpr std::uint32_t kUpdatesLate = 0x10001;
  static constexpr auto kSettle = std::chrono::seconds(2);  // an update at enable and disable
  static constexpr int kAxes = 2;                           // an effect's plane: x and y
  enum CounterIndex : std::size_t {
    kAxisEvents,
    kSuperseded,
    kHeld,
    kEffectUpdates,
    kUpdatesSuperseded,
    kLongestUpdate,
    kLateUpdates,
    kDropped,
    kSilent,
    kOtherEvents,
    kDrainLimit,
    kMalformed,
    kLibrary,
    kCounterCount
  };
  // One axis' state: its range, the frame being read, its last value.
  struct Axis {
    AxisRange range;
    int pending = 0;                      // the axis value of the frame being read
    bool moved = false;                   // the frame being read moved it
    std::int64_t value = 0;               // the last complete frame's, unwrapped (axis.wraps)
    io::CounterUnwrap unwrap{32, false};  // axis.wraps: the value less the range's minimum
    int kernel_fuzz = 0;                  // the fuzz the kernel had on it, given back at close
    std::uint32_t samples = 0;            // this tick's frames that moved it
    std::int64_t time_ns = 0;             // the newest one's kernel time
    std::int64_t quiet_since_ns = 0;      // its last event, or the last zero force after it
  };
  struct Drained {
    std::uint32_t frames = 0;  // frames (SYN_REPORT) that moved an axis
    int error = 0;             // the transport failed (errno)
    bool effect_stopped = false;
  };
  Drained drain() noexcept;
  void take_event(const wire::Event& ev, Drained& d) noexcept;
  void take_frame(Drained& d, std::int64_t time_ns) noexcept;  // the axes' pending values are new
  void check_device(const wire::Facts& f, const AxisSettings& a) const;
  void configure_axis(int j);
  void upload();
  void start_updates();
  UpdateThread::Session session() const noexcept;
  void zero_and_wait(const char* when);
  void stop_effect() noexcept;
  IoStatus hold(int j, PositionSample& out) noexcept;
  void post(double force0, double force1) noexcept;
  std::int64_t unwrapped(int j, int raw) noexcept;
  void check_wrap(const wire::Facts& f, int j);
  void ff_or_throw(int code, int value, const char* what);
  void note_kernel_driver(const InputListing& l);
  std::string describe_late() const;
  void unfuzz(int j, int fuzz);
  void refuzz() noexcept;
  int effect_count() const noexcept;
  bool forced() const noexcept;

  std::shared_ptr<const EvdevSettings> settings_;
  std::function<Opened()> open_;
  double period_s_;
  bool realtime_;
  std::int64_t liveness_ns_;
  int joints_;
  std::unique_ptr<EvdevTransport> transport_;
  std::vector<std::string> notices_;
  std::array<Axis, kAxes> axes_{};
  // The uploaded effects (id -1: none): one, or one per axis (effect: per_axis); the levels
  // (and, effect: direction, the direction) last written.
  std::array<wire::Effect, kAxes> effects_{};
  std::unique_ptr<UpdateThread> updates_;  // from configure to close
  bool active_ = false;
  bool stopping_ = false;  // the stop asked for this session (a fault's, or disable's)
  bool have_position_ = false;
  bool has_gain_ = false, has_autocenter_ = false;
  std::int64_t late_ns_ = 0;  // the longest update of the late streak that faulted
  std::atomic<EvdevTransport*> emergency_{nullptr};
  using K = base::CounterKind;
  std::array<base::Counter, kCounterCount> c_{{
      {"axis_events", K::kCount, "frames (SYN_REPORT) that moved a configured axis"},
      {"superseded", K::kCount, "axis frames replaced by a newer one in the same tick"},
      {"held_ticks", K::kCount, "ticks without an axis event: the position held (each axis')"},
      {"effect_updates", K::kCount, "EVIOCSFF updates of an effect's level the kernel took"},
      {"updates_superseded", K::kCount,
       "levels replaced by a newer one before the update thread took them (the device was "
       "busy with an earlier update)"},
      {"longest_update_us", K::kCount, "the longest EVIOCSFF, us"},
      {"late_updates", K::kAnomaly,
       "EVIOCSFF updates longer than the declared delay covers (device.evdev.update_latency_ms)"},
      {"syn_dropped", K::kAnomaly, "times the kernel's event buffer overflowed (SYN_DROPPED)"},
      {"silent_ticks", K::kAnomaly,
       "ticks past device.evdev.liveness_ms without an event of an axis while a force was "
       "commanded"},
      {"other_events", K::kCount, "events of other axes, keys and buttons (ignored)"},
      {"drain_limit", K::kAnomaly, "ticks that stopped draining at the per-tick bound"},
      {"malformed_messages", K::kAnomaly,
       "loopback messages that were no event, skipped (a broken simulated device)"},
      {"library_messages", K::kAnomaly,
       "messages libevdev logged (counted, not printed): a device bug, a reader falling behind"},
  }};
};

}  // namespace hapticd::drivers::evdev
