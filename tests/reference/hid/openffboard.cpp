#include "openffboard.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hapticd::reference {
namespace {

std::int16_t le16(std::span<const std::uint8_t> r, std::size_t at) {
  return at + 1 < r.size() ? static_cast<std::int16_t>(r[at] | r[at + 1] << 8) : 0;
}

}  // namespace

OpenFfboard::OpenFfboard(const OpenFfboardOptions& o)
    : o_(o),
      axis_(o.inertia, o.damping, o.start_position),
      y_axis_(o.inertia, o.damping, o.start_position_y),
      effects_(o.effects),
      usb_({kVendor, kProduct, 0x0100, "Open FFBoard", "FFBoard", o.serial},
           openffboard_descriptor(o.axes),
           {[this](std::span<const std::uint8_t> r) { output(r); },
            [this](std::span<const std::uint8_t> r) { return create_effect(r); },
            [this](std::uint8_t id) { return get_feature(id); }},
           true),
      loop_([this] { main_loop(); }) {}

OpenFfboard::~OpenFfboard() {
  stop_.store(true);
  loop_.join();
  usb_.unplug();
}

std::int64_t OpenFfboard::now_ms() const {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000 + t.tv_nsec / 1'000'000;
}

std::size_t OpenFfboard::allocated() const {
  const std::lock_guard lock(m_);
  return static_cast<std::size_t>(
      std::count_if(effects_.begin(), effects_.end(), [](const Effect& e) { return e.type != 0; }));
}

bool OpenFfboard::playing() const {
  const std::lock_guard lock(m_);
  return std::any_of(effects_.begin(), effects_.end(), [](const Effect& e) { return e.playing; });
}

// The FFB timer's 1 kHz cycle (FFBHIDMain::update): the axis, then a report every
// usb_report_rate cycles, then the torque. A late cycle catches up by the cycles it missed.
void OpenFfboard::main_loop() {
  timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  std::int64_t last = now_ms();
  int rate_count = 0;
  while (!stop_.load()) {
    next.tv_nsec += 1'000'000;
    if (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    const std::int64_t now = now_ms();
    const int cycles = static_cast<int>(std::clamp<std::int64_t>(now - last, 1, 50));
    last = now;
    if (hung_.load()) {
      axis_.step(cycles * 1e-3, axis_.motor());  // the last torque stays on
      if (o_.axes == 2) y_axis_.step(cycles * 1e-3, y_axis_.motor());
      continue;
    }
    rate_count += cycles;
    if (rate_count >= o_.usb_report_rate) {
      send_report(rate_count / o_.usb_report_rate);
      rate_count %= o_.usb_report_rate;
    }
    const Torques t = torque(now);
    axis_.step(cycles * 1e-3, t.x);
    if (o_.axes == 2) y_axis_.step(cycles * 1e-3, t.y);
  }
}

// FFBHIDMain::send_report: nothing while the endpoint is busy; the gamepad report when it
// changed or when the counter passed 100 / usb_report_rate.
void OpenFfboard::send_report(int calls) {
  if (!usb_.configured()) return;
  const double half_range = o_.degrees / 2.0 * M_PI / 180.0;
  std::vector<std::uint8_t> report(1 + 8 + 16, 0);  // reportHID_t<int16_t>
  report[0] = 1;
  // Axis i into the report's axis i (FFBHIDMain.cpp lines 192-202): X, then Y with two axes.
  for (int i = 0; i < o_.axes; ++i) {
    const double raw = std::nearbyint(axis(i).position() / half_range * 32767.0);
    const auto v = static_cast<std::int16_t>(std::clamp(raw, -32767.0, 32767.0));
    report[9 + 2 * i] = static_cast<std::uint8_t>(v & 0xFF);
    report[10 + 2 * i] = static_cast<std::uint8_t>((v >> 8) & 0xFF);
  }
  send_counter_ += calls;
  if (send_counter_ <= 100 / o_.usb_report_rate && report == last_sent_) return;
  if (!usb_.send_input(report)) return;  // tud_hid_n_ready() false: try next time
  last_sent_ = report;
  send_counter_ = 0;
  reports_.fetch_add(1);
}

// EffectsCalculator::calculateEffects (lines 124-163): every playing effect's share on each
// axis, summed per axis, each sum clipped on its own.
OpenFfboard::Torques OpenFfboard::torque(std::int64_t now) {
  const std::lock_guard lock(m_);
  if (!ffb_active_.load()) return {};
  double sum[2] = {0.0, 0.0};
  for (Effect& e : effects_) {
    if (!e.playing) continue;
    if (e.duration_ms != 0xFFFF && e.duration_ms != 0 &&
        now - e.start_ms > static_cast<std::int64_t>(e.duration_ms)) {
      e.playing = false;  // expired
      continue;
    }
    if (e.type != 1) continue;
    for (int i = 0; i < 2; ++i) sum[i] += e.magnitude * e.axis_magnitude[i] * e.gain / 255.0;
  }
  const auto scale = [&](double f) {
    // calcComponentForce: result_torque = -forceVector * angle_ratio (the header says why).
    if (o_.force_sign == ForceSign::kOpenFfboard) f = -f;
    f = std::clamp(f * device_gain_ / 255.0, -32767.0, 32767.0);
    return f / 32767.0 * o_.torque_full_scale;
  };
  return {scale(sum[0]), o_.axes == 2 ? scale(sum[1]) : 0.0};
}

// HidFFB::hidOut: the report id picks the handler; reports carry their id in byte 0.
void OpenFfboard::output(std::span<const std::uint8_t> r) {
  if (r.size() < 2) return;
  const std::lock_guard lock(m_);
  outputs_.fetch_add(1);
  if (r[0] == 0x05) constant_reports_.fetch_add(1);
  if (r[0] == 0x01) set_effect_reports_.fetch_add(1);
  const std::uint8_t block = r[1];
  Effect* e = block >= 1 && std::size_t{block} <= effects_.size() ? &effects_[block - 1u] : nullptr;
  switch (r[0]) {
    case 0x01:
      set_effect(r);
      break;
    case 0x05:  // set_constant_effect
      if (e != nullptr) e->magnitude = le16(r, 2);
      break;
    case 0x0A:  // set_effect_operation: 1 start, 2 start solo, 3 stop
      if (e == nullptr || r.size() < 3) break;
      if (r[2] == 3) {
        e->playing = false;
        break;
      }
      if (r[2] == 2) {
        for (Effect& other : effects_) other.playing = false;
      }
      e->start_ms = now_ms();
      e->playing = true;
      break;
    case 0x0B:  // free_effect(report[1] - 1)
      if (e != nullptr) *e = Effect{};
      break;
    case 0x0C:
      control(r[1]);
      break;
    case 0x0D:
      device_gain_ = r[1];
      break;
    default:  // envelope, condition, periodic, ramp, commands: not rendered here
      break;
  }
}

void OpenFfboard::set_effect(std::span<const std::uint8_t> r) {
  // FFB_SetEffect_t (ffb_defs.h lines 200-220): id, block, type, duration, trigger repeat,
  // sample period, start delay (u16 each), gain, trigger button, enableAxis, directionX, and
  // with two axes directionY.
  const std::size_t length = o_.axes == 2 ? 18 : 16;
  if (r.size() < length || r[1] == 0 || std::size_t{r[1]} > effects_.size()) return;
  Effect& e = effects_[r[1] - 1u];
  e.type = r[2];
  const auto duration = static_cast<std::uint16_t>(le16(r, 3));
  e.duration_ms = duration == 0 ? 0xFFFF : duration;  // "games assuming 0 is infinite"
  e.gain = r[11];
  // HidFFB.cpp line 17 (the mask 1 << axisCount) and lines 318-321 (the shares).
  const bool direction_enable = (r[13] & (1u << o_.axes)) != 0;
  const double dx = static_cast<std::uint16_t>(le16(r, 14));
  const double dy = o_.axes == 2 ? static_cast<std::uint16_t>(le16(r, 16)) : 0.0;
  const double phase = 2.0 * M_PI * dx / 36000.0;
  e.axis_magnitude[0] = direction_enable ? std::sin(phase)
                        : (r[13] & 0x01) ? (dx - 18000.0) / 18000.0
                                         : 0.0;
  e.axis_magnitude[1] = direction_enable ? -std::cos(phase)
                        : (r[13] & 0x02) ? -(dy - 18000.0) / 18000.0
                                         : 0.0;
  if (!ffb_active_.load()) ffb_active_.store(true);  // start_FFB()
  status_report();
}

void OpenFfboard::control(std::uint8_t bits) {
  if (bits & 0x01) ffb_active_.store(true);
  if (bits & (0x02 | 0x04 | 0x10)) ffb_active_.store(false);
  if (bits & 0x08) {
    ffb_active_.store(false);
    for (Effect& e : effects_) e = Effect{};  // reset_ffb()
  }
  if (bits & 0x20) ffb_active_.store(true);
}

// SET_REPORT of feature 0x11, Create New Effect (the stack strips nothing here: id first).
bool OpenFfboard::create_effect(std::span<const std::uint8_t> r) {
  if (r.size() < 2 || r[0] != 0x11) return false;
  const std::lock_guard lock(m_);
  const std::uint8_t type = r[1];
  auto free =
      std::find_if(effects_.begin(), effects_.end(), [](const Effect& e) { return e.type == 0; });
  if (type == 0 || type > 12 || free == effects_.end()) {
    load_status_ = 2;  // full (an invalid type reads as full too: find_free_effect's -1)
    return true;
  }
  *free = Effect{};
  free->type = type;
  load_index_ = static_cast<std::uint8_t>(free - effects_.begin() + 1);
  load_status_ = 1;
  status_report();
  return true;
}

std::optional<std::vector<std::uint8_t>> OpenFfboard::get_feature(std::uint8_t id) {
  const std::lock_guard lock(m_);
  const std::size_t used = static_cast<std::size_t>(
      std::count_if(effects_.begin(), effects_.end(), [](const Effect& e) { return e.type != 0; }));
  constexpr std::uint16_t kEffectBytes = 80;  // sizeof(FFB_Effect), roughly: a RAM figure
  if (id == 0x12) {                           // FFB_BlockLoad_Feature_Data_t
    const auto pool = static_cast<std::uint16_t>((effects_.size() - used) * kEffectBytes);
    return std::vector<std::uint8_t>{load_index_, load_status_,
                                     static_cast<std::uint8_t>(pool & 0xFF),
                                     static_cast<std::uint8_t>(pool >> 8)};
  }
  if (id == 0x13) {  // FFB_PIDPool_Feature_Data_t: memoryManagement 1 = device managed
    const auto size = static_cast<std::uint16_t>(effects_.size() * kEffectBytes);
    return std::vector<std::uint8_t>{static_cast<std::uint8_t>(size & 0xFF),
                                     static_cast<std::uint8_t>(size >> 8),
                                     static_cast<std::uint8_t>(effects_.size()), 1};
  }
  return std::nullopt;  // HidFFB::hidGet answers nothing else (a zero-length reply)
}

// HidFFB::sendStatusReport: Actuator Power always; enabled and playing, or paused.
void OpenFfboard::status_report() {
  const std::uint8_t bits = ffb_active_.load() ? 0x08 | 0x02 | 0x10 : 0x08 | 0x01;
  const std::uint8_t report[2] = {2, bits};
  usb_.send_input(report);  // tud_hid_report: dropped when the endpoint is busy
}

}  // namespace hapticd::reference
