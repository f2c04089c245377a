#include "drivers/evdev/evdev_device.h"

#include <cerrno>
#include <cmath>
#include <limits>

#include "base/clock.h"
#include "base/errno_text.h"
#include "config/schema_reader.h"

namespace hapticd::drivers::evdev {
namespace {

// FF_GAIN and FF_AUTOCENTER take 0..0xffff.
int fraction16(double f) { return static_cast<int>(std::lround(f * 0xFFFF)); }

}  // namespace

EvdevDevice::EvdevDevice(std::shared_ptr<const EvdevSettings> settings,
                         std::function<Opened()> open, double sample_period_s, bool realtime)
    : settings_(std::move(settings)),
      open_(std::move(open)),
      period_s_(sample_period_s),
      realtime_(realtime),
      liveness_ns_(static_cast<std::int64_t>(settings_->liveness_ms * 1e6)) {}

EvdevDevice::~EvdevDevice() { close(); }

// The kernel smooths an axis with fuzz (hid-input gives a joystick's 1/256 of its range): a
// change within fuzz/2 is dropped and up to twice fuzz averaged with the last value, a dead
// band and a lag in the position the wall is rendered from. hapticd turns it off while it has
// the device and gives it back at close.
void EvdevDevice::unfuzz(int fuzz) {
  kernel_fuzz_ = 0;
  if (fuzz == 0) return;
  transport_->set_fuzz(settings_->axis.code, 0);
  kernel_fuzz_ = fuzz;
  notices_.push_back("the kernel filtered " + abs_name(settings_->axis.code) + " with fuzz " +
                     std::to_string(fuzz) + " (changes within " + std::to_string(fuzz / 2) +
                     " counts dropped): hapticd sets it to 0 while it runs and gives it back at "
                     "close");
}

std::int64_t EvdevDevice::unwrapped(int raw) noexcept {
  if (!settings_->axis.wraps) return raw;
  const auto from_min = static_cast<std::uint64_t>(std::int64_t{raw} - range_.minimum);
  return range_.minimum + unwrap_.next(from_min);
}

// The update thread, at SCHED_FIFO one below the loop, timing each update against what the
// declared delay covers (in a realtime loop: in freerun an update's wall time delays nothing).
void EvdevDevice::start_updates() {
  const UpdateThread::Timing timing{
      realtime_ ? static_cast<std::int64_t>(covered_update_s(*settings_, period_s_) * 1e9)
                : std::numeric_limits<std::int64_t>::max(),
      settings_->late_update_fault};
  updates_ = std::make_unique<UpdateThread>(
      *transport_, settings_->writer_priority, timing,
      UpdateThread::Counters{c_[kEffectUpdates], c_[kLateUpdates], c_[kLongestUpdate]});
  updates_->start_session(effect_);
}

void EvdevDevice::upload() {
  effect_ = {};
  effect_.direction = direction_of(settings_->direction_deg);
  effect_.id = static_cast<std::int16_t>(transport_->upload(effect_));
  transport_->set_emergency_effect(effect_.id);
}

DeviceInfo EvdevDevice::on_configure() {
  for (base::Counter& c : c_) c.set(0);
  notices_.clear();
  active_ = false;
  have_position_ = false;
  effect_ = {};
  Opened o = open_();
  transport_ = std::move(o.transport);
  const wire::Facts f = transport_->facts(settings_->axis.code);
  check_device(f);
  range_ = f.range;
  check_wrap(f);
  unfuzz(f.fuzz);
  has_gain_ = f.ff_gain;
  has_autocenter_ = f.ff_autocenter;
  if (has_gain_) ff_or_throw(kFfGain, fraction16(settings_->gain), "FF_GAIN");
  if (has_autocenter_)
    ff_or_throw(kFfAutocenter, fraction16(settings_->autocenter), "FF_AUTOCENTER");
  upload();
  start_updates();
  emergency_.store(transport_.get());
  if (o.listing) note_kernel_driver(*o.listing);
  return {transport_->describe() + ", " + abs_name(settings_->axis.code) + ", ff_driver " +
              to_string(settings_->ff_driver),
          declared_delay_samples(*settings_, period_s_), 0};
}

void EvdevDevice::ff_or_throw(int code, int value, const char* what) {
  if (const int e = transport_->write_ff(code, value); e != 0) {
    throw DeviceError(std::string("evdev: setting ") + what + ": " + base::errno_text(e));
  }
}

void EvdevDevice::on_enable() {
  transport_->grab(true);
  if (effect_.id < 0) upload();  // a disable erased it
  // Whatever the device said before output was enabled is not this run's: the kernel's
  // current value is.
  wire::Event ev;
  int error = 0;
  for (int i = 0; i < kMaxDrain; ++i) {
    const ReadStatus r = transport_->read(ev, error);
    if (r == ReadStatus::kEmpty) break;
    if (r == ReadStatus::kError)
      throw DeviceError("evdev: reading at enable: " + base::errno_text(error));
  }
  const wire::Facts f = transport_->facts(settings_->axis.code);
  value_ = unwrapped(f.value);
  frame_moved_ = false;
  have_position_ = true;
  if (has_autocenter_) ff_or_throw(kFfAutocenter, 0, "FF_AUTOCENTER");  // hapticd renders alone
  updates_->start_session(effect_);
  stopping_ = false;
  zero_and_wait("at enable");
  if (const int e = updates_->error(); e != 0) {
    throw DeviceError("evdev: EVIOCSFF at enable: " + base::errno_text(e));
  }
  ff_or_throw(effect_.id, 1, "the effect playing");
  quiet_since_ns_ = base::monotonic_ns();
  active_ = true;
}

// Level 0 through the update thread, and its EVIOCSFF awaited (not on the RT thread).
void EvdevDevice::zero_and_wait(const char* when) {
  post(0);
  if (!updates_->flush(kSettle)) {
    throw DeviceError(std::string("evdev: the device did not take an update ") + when + " within " +
                      std::to_string(kSettle.count()) + " s (device.evdev.update_latency_ms " +
                      config::schema::format_number(settings_->update_latency_ms) + ")");
  }
}

// RT-safe, once a session: the update thread stops the effect right after the update it has in
// hand (the kernel lets nothing through the node before that one is answered), then makes
// level 0, which replaces any level still waiting. The RT thread makes no system call for it
// but a wake.
void EvdevDevice::stop_effect() noexcept {
  if (effect_.id < 0 || stopping_) return;
  stopping_ = true;
  effect_.level = 0;
  if (updates_->post_stop()) c_[kUpdatesSuperseded].add();
}

void EvdevDevice::on_disable() noexcept {
  active_ = false;
  if (!transport_) return;
  stop_effect();
  // The stop and level 0 made before the effect is erased (an update in hand would meet an
  // erased id). A device that does not answer in time: the erase waits for it in the kernel.
  updates_->flush(kSettle);
  if (effect_.id >= 0) {
    transport_->set_emergency_effect(-1);
    transport_->erase(effect_.id);
    effect_.id = -1;
  }
  if (has_autocenter_) transport_->write_ff(kFfAutocenter, fraction16(settings_->autocenter));
  try {
    transport_->grab(false);
  } catch (const DeviceError&) {
    // A device that is gone has no grab left to release.
  }
}

void EvdevDevice::on_close() noexcept {
  active_ = false;
  emergency_.store(nullptr);
  updates_.reset();  // joined before the transport it updates through goes
  if (transport_ && effect_.id >= 0) transport_->erase(effect_.id);
  effect_.id = -1;
  if (transport_ && kernel_fuzz_ != 0) {
    try {
      transport_->set_fuzz(settings_->axis.code, kernel_fuzz_);
    } catch (const DeviceError&) {
      // A device that is gone takes its fuzz with it.
    }
    kernel_fuzz_ = 0;
  }
  transport_.reset();  // closing the node also erases whatever effect this process left
}

// The stop of the effect, write(2) on the open node from the crash handler: the kernel lets it
// through once the update the device has in hand is answered (evdev's node mutex).
void EvdevDevice::emergency_stop() noexcept {
  if (EvdevTransport* t = emergency_.load()) t->emergency();
}

void EvdevDevice::wait_output() const noexcept {
  if (updates_) updates_->wait_done();
}

EvdevDevice::Drained EvdevDevice::drain() noexcept {
  Drained d;
  wire::Event ev;
  int i = 0;
  for (; i < kMaxDrain; ++i) {
    const ReadStatus r = transport_->read(ev, d.error);
    if (r == ReadStatus::kEmpty) break;
    if (r == ReadStatus::kError) return d;
    if (r == ReadStatus::kMalformed) {
      c_[kMalformed].add();
      continue;
    }
    if (r == ReadStatus::kDropped) {
      c_[kDropped].add();
      // libevdev took the cut-off frame's axis value into its state, and its resync repeats
      // only what differs from that state: the value stands, or the axis would never get it.
      if (frame_moved_) take_frame(d, ev.time_ns);
      continue;
    }
    if (ev.type == kEvAbs && ev.code == settings_->axis.code) {
      pending_value_ = ev.value;
      frame_moved_ = true;
    } else if (ev.type == kEvSyn && ev.code == kSynReport) {
      if (frame_moved_) take_frame(d, ev.time_ns);
    } else if (ev.type == kEvFfStatus && ev.code == effect_.id && ev.value == kFfStatusStopped) {
      d.effect_stopped = true;
    } else if (ev.type != kEvSyn) {
      c_[kOtherEvents].add();
    }
  }
  if (i == kMaxDrain) c_[kDrainLimit].add();
  c_[kLibrary].set(transport_->library_messages());
  return d;
}

void EvdevDevice::take_frame(Drained& d, std::int64_t time_ns) noexcept {
  value_ = unwrapped(pending_value_);
  frame_moved_ = false;
  if (d.samples > 0) c_[kSuperseded].add();
  ++d.samples;
  c_[kAxisEvents].add();
  d.time_ns = time_ns;
}

IoStatus EvdevDevice::on_read(std::span<PositionSample> samples) noexcept {
  PositionSample& out = samples.front();  // one joint
  const Drained d = drain();
  if (d.error != 0) {
    set_fault_code(static_cast<std::uint32_t>(d.error));
    return IoStatus::kTransportFault;
  }
  if (active_ && d.effect_stopped) {
    set_fault_code(kEffectStopped);
    return IoStatus::kDeviceFault;
  }
  if (d.samples == 0) return hold(out);
  have_position_ = true;
  quiet_since_ns_ = base::monotonic_ns();
  out.position = axis_position(value_, settings_->axis, range_);
  out.time_ns = d.time_ns;
  out.flags = kSampleHasTime;
  out.samples = d.samples;
  return IoStatus::kOk;
}

// A tick without an axis event: the input core passes a value only when it changes, so the
// position is the last one, still current - unless a force has been commanded for longer than
// the liveness bound without the axis saying anything: then it is stale (the loop counts it).
IoStatus EvdevDevice::hold(PositionSample& out) noexcept {
  if (!have_position_) return IoStatus::kNoNewData;
  const std::int64_t now = base::monotonic_ns();
  if (liveness_ns_ > 0 && effect_.level != 0 && now - quiet_since_ns_ > liveness_ns_) {
    c_[kSilent].add();
    return IoStatus::kNoNewData;
  }
  c_[kHeld].add();
  out.position = axis_position(value_, settings_->axis, range_);
  out.time_ns = now;  // nothing changed up to now: the position is current as of now
  out.flags = kSampleHasTime | kSampleHeld;
  return IoStatus::kOk;
}

// RT-safe: called every tick. The update thread counts what the kernel took (effect_updates);
// a level replaced before it was taken is counted here.
void EvdevDevice::post(std::int16_t level) noexcept {
  effect_.level = level;
  if (updates_->post(level)) c_[kUpdatesSuperseded].add();
}

// RT-safe: called every tick. A refused update, or late_update_fault late ones in a row, is
// the run's transport fault at the next write: the level is handed on, never waited for.
IoStatus EvdevDevice::on_write(std::span<const double> forces) noexcept {
  const double force = forces.front();     // one joint
  if (state() == DeviceState::kFaulted) {  // nothing but zero, and the effect stopped
    stop_effect();
    return IoStatus::kOk;
  }
  if (const int e = updates_->error(); e != 0) {
    set_fault_code(static_cast<std::uint32_t>(e));
    return IoStatus::kTransportFault;
  }
  if (updates_->late()) {
    late_ns_ = updates_->late_ns();
    set_fault_code(kUpdatesLate);
    return IoStatus::kTransportFault;
  }
  const std::int16_t level = force_level(force, settings_->force_full_scale);
  if (level == 0) quiet_since_ns_ = base::monotonic_ns();  // nothing is pushed: silence is fine
  post(level);
  return IoStatus::kOk;
}

}  // namespace hapticd::drivers::evdev
