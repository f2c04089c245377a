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
      liveness_ns_(static_cast<std::int64_t>(settings_->liveness_ms * 1e6)),
      joints_(settings_->joints) {}

EvdevDevice::~EvdevDevice() { close(); }

std::int64_t EvdevDevice::unwrapped(int j, int raw) noexcept {
  if (!settings_->axis_of(j).wraps) return raw;
  Axis& a = axes_[j];
  const auto from_min = static_cast<std::uint64_t>(std::int64_t{raw} - a.range.minimum);
  return a.range.minimum + a.unwrap.next(from_min);
}

int EvdevDevice::effect_count() const noexcept {
  return joints_ == 2 && settings_->effect == EffectMode::kPerAxis ? 2 : 1;
}

UpdateThread::Session EvdevDevice::session() const noexcept {
  UpdateThread::Session s;
  s.effects = effects_;
  s.mode = joints_ == 1                                ? UpdateThread::Mode::kOne
           : settings_->effect == EffectMode::kPerAxis ? UpdateThread::Mode::kPerAxis
                                                       : UpdateThread::Mode::kDirected;
  return s;
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
  updates_->start_session(session());
}

// One effect (one axis: direction_deg; two: the direction follows the force), or one per axis
// at its fixed direction (effect: per_axis).
void EvdevDevice::upload() {
  const bool per_axis = effect_count() == 2;
  for (int k = 0; k < effect_count(); ++k) {
    wire::Effect& e = effects_[k];
    e = {};
    e.direction = direction_of(joints_ == 1 ? settings_->direction_deg
                                            : settings_->axis_of(per_axis ? k : 0).direction_deg);
    e.id = static_cast<std::int16_t>(transport_->upload(e));
  }
  transport_->set_emergency_effects(effects_[0].id, per_axis ? effects_[1].id : -1);
}

void EvdevDevice::configure_axis(int j) {
  const AxisSettings& a = settings_->axis_of(j);
  const wire::Facts f = transport_->facts(a.code);
  check_device(f, a);
  if (f.ff_effects < effect_count()) {
    throw DeviceError("evdev: \"" + f.name + "\" holds " + std::to_string(f.ff_effects) +
                      " force-feedback effect(s) at once; device.evdev.effect per_axis needs 2 "
                      "(effect: direction needs 1)");
  }
  axes_[j] = {};
  axes_[j].range = f.range;
  check_wrap(f, j);
  unfuzz(j, f.fuzz);
  if (j > 0) return;
  has_gain_ = f.ff_gain;
  has_autocenter_ = f.ff_autocenter;
}

DeviceInfo EvdevDevice::on_configure() {
  for (base::Counter& c : c_) c.set(0);
  notices_.clear();
  active_ = false;
  have_position_ = false;
  effects_ = {};
  Opened o = open_();
  transport_ = std::move(o.transport);
  for (int j = 0; j < joints_; ++j) configure_axis(j);
  if (has_gain_) ff_or_throw(kFfGain, fraction16(settings_->gain), "FF_GAIN");
  if (has_autocenter_)
    ff_or_throw(kFfAutocenter, fraction16(settings_->autocenter), "FF_AUTOCENTER");
  upload();
  start_updates();
  emergency_.store(transport_.get());
  if (o.listing) note_kernel_driver(*o.listing);
  std::string axes = abs_name(settings_->axis.code);
  if (joints_ == 2) {
    axes += " and " + abs_name(settings_->second.code) + ", effect " + to_string(settings_->effect);
  }
  DeviceInfo info{
      transport_->describe() + ", " + axes + ", ff_driver " + to_string(settings_->ff_driver),
      declared_delay_samples(*settings_, period_s_), 0};
  info.joints = static_cast<std::size_t>(joints_);
  return info;
}

void EvdevDevice::ff_or_throw(int code, int value, const char* what) {
  if (const int e = transport_->write_ff(code, value); e != 0) {
    throw DeviceError(std::string("evdev: setting ") + what + ": " + base::errno_text(e));
  }
}

void EvdevDevice::on_enable() {
  transport_->grab(true);
  if (effects_[0].id < 0) upload();  // a disable erased them
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
  for (int j = 0; j < joints_; ++j) {
    const wire::Facts f = transport_->facts(settings_->axis_of(j).code);
    axes_[j].value = unwrapped(j, f.value);
    axes_[j].moved = false;
  }
  have_position_ = true;
  if (has_autocenter_) ff_or_throw(kFfAutocenter, 0, "FF_AUTOCENTER");  // hapticd renders alone
  updates_->start_session(session());
  stopping_ = false;
  zero_and_wait("at enable");
  if (const int e = updates_->error(); e != 0) {
    throw DeviceError("evdev: EVIOCSFF at enable: " + base::errno_text(e));
  }
  for (int k = 0; k < effect_count(); ++k) ff_or_throw(effects_[k].id, 1, "the effect playing");
  const std::int64_t now = base::monotonic_ns();
  for (int j = 0; j < joints_; ++j) axes_[j].quiet_since_ns = now;
  active_ = true;
}

// Level 0 through the update thread, and its EVIOCSFF awaited (not on the RT thread).
void EvdevDevice::zero_and_wait(const char* when) {
  post(0.0, 0.0);
  if (!updates_->flush(kSettle)) {
    throw DeviceError(std::string("evdev: the device did not take an update ") + when + " within " +
                      std::to_string(kSettle.count()) + " s (device.evdev.update_latency_ms " +
                      config::schema::format_number(settings_->update_latency_ms) + ")");
  }
}

// RT-safe, once a session: the update thread stops the effects right after the update it has
// in hand (the kernel lets nothing through the node before that one is answered), then makes
// level 0, which replaces any level still waiting. The RT thread makes no system call for it
// but a wake.
void EvdevDevice::stop_effect() noexcept {
  if (effects_[0].id < 0 || stopping_) return;
  stopping_ = true;
  for (wire::Effect& e : effects_) e.level = 0;
  if (updates_->post_stop(effects_[0].direction)) c_[kUpdatesSuperseded].add();
}

void EvdevDevice::on_disable() noexcept {
  active_ = false;
  if (!transport_) return;
  stop_effect();
  // The stop and level 0 made before the effects are erased (an update in hand would meet an
  // erased id). A device that does not answer in time: the erase waits for it in the kernel.
  updates_->flush(kSettle);
  if (effects_[0].id >= 0) {
    transport_->set_emergency_effects(-1, -1);
    for (int k = 0; k < effect_count(); ++k) transport_->erase(effects_[k].id);
    for (wire::Effect& e : effects_) e.id = -1;
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
  for (int k = 0; transport_ && k < effect_count(); ++k) {
    if (effects_[k].id >= 0) transport_->erase(effects_[k].id);
  }
  for (wire::Effect& e : effects_) e.id = -1;
  refuzz();
  transport_.reset();  // closing the node also erases whatever effect this process left
}

// The stop of the effects, write(2) on the open node from the crash handler: the kernel lets it
// through once the update the device has in hand is answered (evdev's node mutex).
void EvdevDevice::emergency_stop() noexcept {
  if (EvdevTransport* t = emergency_.load()) t->emergency();
}

void EvdevDevice::wait_output() const noexcept {
  if (updates_) updates_->wait_done();
}

// RT-safe: called every tick. The pending events, at most kMaxDrain.
EvdevDevice::Drained EvdevDevice::drain() noexcept {
  Drained d;
  for (int j = 0; j < joints_; ++j) axes_[j].samples = 0;
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
      // libevdev took the cut-off frame's axis values into its state, and its resync repeats
      // only what differs from that state: the values stand, or the axes would never get them.
      take_frame(d, ev.time_ns);
      continue;
    }
    take_event(ev, d);
  }
  if (i == kMaxDrain) c_[kDrainLimit].add();
  c_[kLibrary].set(transport_->library_messages());
  return d;
}

// RT-safe: called every tick. One event: a configured axis' value, the end of a frame, the
// device stopping an effect of hapticd's, or something else (counted).
void EvdevDevice::take_event(const wire::Event& ev, Drained& d) noexcept {
  if (ev.type == kEvAbs) {
    for (int j = 0; j < joints_; ++j) {
      if (ev.code != settings_->axis_of(j).code) continue;
      axes_[j].pending = ev.value;
      axes_[j].moved = true;
      return;
    }
  } else if (ev.type == kEvSyn && ev.code == kSynReport) {
    take_frame(d, ev.time_ns);
    return;
  } else if (ev.type == kEvFfStatus && ev.value == kFfStatusStopped) {
    for (int k = 0; k < effect_count(); ++k) {
      if (ev.code == effects_[k].id) d.effect_stopped = true;
    }
    if (d.effect_stopped) return;
  }
  if (ev.type != kEvSyn) c_[kOtherEvents].add();
}

// RT-safe: called every tick. A frame that moved no configured axis is nothing to the driver.
void EvdevDevice::take_frame(Drained& d, std::int64_t time_ns) noexcept {
  bool any = false;
  for (int j = 0; j < joints_; ++j) {
    Axis& a = axes_[j];
    if (!a.moved) continue;
    a.value = unwrapped(j, a.pending);
    a.moved = false;
    ++a.samples;
    a.time_ns = time_ns;
    any = true;
  }
  if (!any) return;
  if (d.frames > 0) c_[kSuperseded].add();
  ++d.frames;
  c_[kAxisEvents].add();
}

// RT-safe: called every tick. Each joint's sample: new where its axis moved, held otherwise.
IoStatus EvdevDevice::on_read(std::span<PositionSample> samples) noexcept {
  const Drained d = drain();
  if (d.error != 0) {
    set_fault_code(static_cast<std::uint32_t>(d.error));
    return IoStatus::kTransportFault;
  }
  if (active_ && d.effect_stopped) {
    set_fault_code(kEffectStopped);
    return IoStatus::kDeviceFault;
  }
  IoStatus status = IoStatus::kOk;
  for (int j = 0; j < joints_; ++j) {
    const Axis& a = axes_[j];
    PositionSample& out = samples[static_cast<std::size_t>(j)];
    if (a.samples == 0) {
      if (hold(j, out) != IoStatus::kOk) status = IoStatus::kNoNewData;
      continue;
    }
    have_position_ = true;
    axes_[j].quiet_since_ns = base::monotonic_ns();
    out.position = axis_position(a.value, settings_->axis_of(j), a.range);
    out.time_ns = a.time_ns;
    out.flags = kSampleHasTime;
    out.samples = a.samples;
  }
  return status;
}

// RT-safe: called every tick. Whether a force is commanded on any joint: silence under it is
// what liveness_ms bounds.
bool EvdevDevice::forced() const noexcept {
  return effects_[0].level != 0 || effects_[1].level != 0;
}

// RT-safe: called every tick. A tick without an event of axis j: the input core passes a value only
// when it changes, so the position is the last one, still current - unless a force has been
// commanded for longer than the liveness bound without the axis saying anything: then it is stale
// (the loop counts it).
IoStatus EvdevDevice::hold(int j, PositionSample& out) noexcept {
  if (!have_position_) return IoStatus::kNoNewData;
  const std::int64_t now = base::monotonic_ns();
  if (liveness_ns_ > 0 && forced() && now - axes_[j].quiet_since_ns > liveness_ns_) {
    c_[kSilent].add();
    return IoStatus::kNoNewData;
  }
  c_[kHeld].add();
  out.position = axis_position(axes_[j].value, settings_->axis_of(j), axes_[j].range);
  out.time_ns = now;  // nothing changed up to now: the position is current as of now
  out.flags = kSampleHasTime | kSampleHeld;
  return IoStatus::kOk;
}

// RT-safe: called every tick. The update thread counts what the kernel took (effect_updates);
// an update replaced before it was taken is counted here. One axis: the level along
// direction_deg; two: the one effect's direction and level, or each axis' effect's level.
void EvdevDevice::post(double force0, double force1) noexcept {
  const double fs = settings_->force_full_scale;
  bool superseded = false;
  if (joints_ == 1) {
    effects_[0].level = force_level(force0, fs);
    superseded = updates_->post(effects_[0].level);
  } else if (settings_->effect == EffectMode::kPerAxis) {
    effects_[0].level = force_level(force0, fs);
    effects_[1].level = force_level(force1, fs);
    superseded = updates_->post(effects_[0].level, static_cast<std::uint16_t>(effects_[1].level));
  } else {
    const DirectedLevel e = directed_level(force0, force1, *settings_, effects_[0].direction);
    effects_[0].level = e.level;
    effects_[0].direction = e.direction;
    superseded = updates_->post(e.level, e.direction);
  }
  if (superseded) c_[kUpdatesSuperseded].add();
}

// RT-safe: called every tick. A refused update, or late_update_fault late ones in a row, is
// the run's transport fault at the next write: the level is handed on, never waited for.
IoStatus EvdevDevice::on_write(std::span<const double> forces) noexcept {
  if (state() == DeviceState::kFaulted) {  // nothing but zero, and the effects stopped
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
  post(forces[0], joints_ == 2 ? forces[1] : 0.0);
  if (forced()) return IoStatus::kOk;
  // Nothing is pushed: silence is fine.
  for (int j = 0; j < joints_; ++j) axes_[j].quiet_since_ns = base::monotonic_ns();
  return IoStatus::kOk;
}

}  // namespace hapticd::drivers::evdev
