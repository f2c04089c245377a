#include "arduino_ffb.h"

#include <time.h>

#include <algorithm>
#include <cmath>

#include "arduino_ffb_descriptor.h"

namespace hapticd::reference {
namespace {

namespace id = arduino_ffb;

constexpr std::uint8_t kAllocated = 0x01, kPlaying = 0x02;  // MEFFECTSTATE_*
constexpr std::uint8_t kDirectionEnable = 0x04;             // DIRECTION_ENABLE
constexpr std::uint16_t kInfinite = 0x7FFF;                 // USB_DURATION_INFINITE
constexpr std::uint16_t kEffectBytes = 63;  // sizeof(TEffectState) on the AVR (no padding)
constexpr std::int32_t kGain = 100;         // Gains: totalGain, constantGain (the sketch's)
constexpr int kSendTimeoutMs = 250;         // USB_Send's wait for the endpoint

std::uint16_t le16(std::span<const std::uint8_t> r, std::size_t at) {
  return at + 1 < r.size() ? static_cast<std::uint16_t>(r[at] | r[at + 1] << 8) : 0;
}

// Arduino's map(): long arithmetic, C's division.
long arduino_map(long x, long in_min, long in_max, long out_min, long out_max) {
  return (x - in_min) * (out_max - out_min) / (in_max - in_min) + out_min;
}

}  // namespace

ArduinoFfb::ArduinoFfb(const ArduinoFfbOptions& o)
    : o_(o),
      axis_(o.inertia, o.damping, o.start_position),
      // The firmware sends its structures whole, their reportId field first: no id prepended.
      usb_({kVendor, kProduct, 0x0100, "Arduino LLC", "Arduino Leonardo", o.serial},
           arduino_ffb_descriptor(),
           {[this](std::span<const std::uint8_t> r) { output(r); },
            [this](std::span<const std::uint8_t> r) { return set_feature(r); },
            [this](std::uint8_t i) { return get_feature(i); }},
           false),
      loop_([this] { sketch_loop(); }) {}

ArduinoFfb::~ArduinoFfb() {
  stop_.store(true);
  loop_.join();
  usb_.unplug();
}

std::int64_t ArduinoFfb::now_ms() const {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000 + t.tv_nsec / 1'000'000;
}

int ArduinoFfb::next_effect_id() const {
  const std::lock_guard lock(m_);
  return next_eid_;
}

std::string ArduinoFfb::describe() const {
  const std::lock_guard lock(m_);
  std::string s =
      "nextEID " + std::to_string(next_eid_) + ", PWM " + std::to_string(pwm_.load()) + ", " +
      std::to_string(reports_.load()) + " reports (" + std::to_string(dropped_.load()) +
      " dropped, the longest USB_Send wait " + std::to_string(longest_wait_ms_.load()) + " ms), " +
      std::to_string(outputs_.load()) + " outputs (" + std::to_string(constants_.load()) +
      " Set Constant Force), position " + std::to_string(axis_.position()) + " rad; PWM changes:";
  for (const std::string& c : changes_) s += "\n  " + c;
  s += "\nSet Constant Force from " + std::to_string(first_constant_ms_ % 100000) + " to " +
       std::to_string(last_constant_ms_ % 100000) + " ms; the other reports (ms, bytes):";
  for (const std::string& c : commands_) s += "\n  " + c;
  return s;
}

// For a test that failed: what the host asked besides the force, in order (m_ held).
void ArduinoFfb::note_command(std::span<const std::uint8_t> r) {
  if (commands_.size() >= 60) return;
  std::string c = std::to_string(now_ms() % 100000) + ":";
  for (std::size_t i = 0; i < r.size() && i < 14; ++i) c += " " + std::to_string(r[i]);
  commands_.push_back(c);
}

bool ArduinoFfb::playing() const {
  const std::lock_guard lock(m_);
  for (const Effect& e : effects_) {
    if (e.state == kPlaying && (e.elapsed <= e.duration || e.duration == kInfinite)) return true;
  }
  return false;
}

// The board's millisecond: the axis moves under the PWM last written; the timer interrupt's
// getForce sets the PWM from what the host last sent; the sketch's loop sends a joystick report
// every report_ms (USB_Send, the Arduino core's USBCore.cpp: it waits while the endpoint holds
// the last report, up to 250 ms, then drops this one; at once while the host has not configured
// the board). A hung sketch sends nothing more; the interrupt still runs.
void ArduinoFfb::sketch_loop() {
  timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  std::int64_t last = now_ms();
  int since_report = 0, waited = 0;
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
    axis_.step(cycles * 1e-3, pwm_.load() / 255.0 * o_.stall_torque);
    pwm_.store(force_calculator(now));
    since_report += cycles;
    if (hung_.load() || since_report < o_.report_ms || !usb_.configured()) continue;
    if (usb_.send_input(joystick_report())) {
      if (reports_.fetch_add(1) > 50) {  // the host reads them: how long this one waited
        longest_wait_ms_.store(std::max<std::int64_t>(longest_wait_ms_, waited));
      }
    } else if ((waited += cycles) < kSendTimeoutMs) {
      continue;
    } else {
      dropped_.fetch_add(1);
    }
    since_report = 0;
    waited = 0;
  }
}

// Joystick_::sendState: report 1, the 8 buttons, then X, Y, Rx, Ry (buildAndSet16BitValue:
// clamped to the range set, mapped onto -32767..32767; here the same range).
std::vector<std::uint8_t> ArduinoFfb::joystick_report() const {
  const double counts = std::nearbyint(axis_.position() * o_.counts_per_rad);
  const long value = static_cast<long>(std::clamp(counts, -32767.0, 32767.0));
  const auto x = static_cast<std::int16_t>(arduino_map(value, -32767, 32767, -32767, 32767));
  std::vector<std::uint8_t> r(1 + 1 + 4 * 2, 0);
  r[0] = id::kJoystickInput;
  r[2] = static_cast<std::uint8_t>(x & 0xFF);
  r[3] = static_cast<std::uint8_t>((x >> 8) & 0xFF);
  return r;
}

// Joystick_::forceCalculator for X: the playing effects' forces, the total gain, then map()
// onto the PWM.
int ArduinoFfb::force_calculator(std::int64_t now) {
  const std::lock_guard lock(m_);
  std::int32_t force = 0;
  for (int i = 0; i < kMaxEffects; ++i) {  // `id < MAX_EFFECTS`: block 14 never plays
    Effect& e = effects_[i];
    if (e.state == kPlaying && (e.elapsed <= e.duration || e.duration == kInfinite) && !paused_) {
      force += effect_force(e, now);
    }
  }
  force = static_cast<std::int32_t>(1.0f * static_cast<float>(force) * kGain / 10000);
  const int pwm = static_cast<int>(arduino_map(force, -10000, 10000, -250, 250));
  if (pwm != pwm_.load()) note_change(now, pwm);
  return pwm;
}

// For a test that failed: the first PWM changes, each with the effects behind it (m_ held).
void ArduinoFfb::note_change(std::int64_t now, int pwm) {
  if (changes_.size() >= 60) changes_.erase(changes_.begin() + 20);  // the first 20, the last 40
  std::string c = std::to_string(now % 100000) + " ms: " + std::to_string(pwm);
  for (int i = 0; i <= kMaxEffects; ++i) {
    const Effect& e = effects_[i];
    if (e.state == 0) continue;
    c += " [block " + std::to_string(i) + " state " + std::to_string(e.state) + " type " +
         std::to_string(e.type) + " magnitude " + std::to_string(e.magnitude) + " gain " +
         std::to_string(e.gain) + " direction " + std::to_string(e.dir_x) + " elapsed " +
         std::to_string(e.elapsed) + "/" + std::to_string(e.duration) + "]";
  }
  changes_.push_back(c);
}

// getEffectForce for a constant force along X: ApplyEnvelope (no envelope: the value itself,
// see the header for a magnitude of 0) times the constant gain and sin(direction).
std::int32_t ArduinoFfb::effect_force(Effect& e, std::int64_t now) {
  std::int32_t force = 0;
  if (e.type == 1) {
    const std::uint8_t direction = e.dir_x;  // X either way: DIRECTION_ENABLE or not
    const float angle =
        (static_cast<float>(direction) * 360.0f / 255.0f) * (3.14159265359f / 180.0f);
    const float ratio = std::sin(angle);
    const std::int32_t gained = static_cast<std::int32_t>(e.magnitude) * e.gain / 255;
    const std::int32_t value = gained != 0 ? gained * e.magnitude / gained : 0;
    force = static_cast<std::int32_t>(static_cast<float>(value * kGain) * ratio);
  }
  // The board's millis() never runs behind a start its USB interrupt made; here `now` was read
  // by the loop before it took the lock, and a start the host's thread made since is later:
  // unclamped, the uint16 wrapped to ~65530 ms, past any duration, and the effect never played
  // again (the cause of this board's kernel tests failing now and then, at the enable's start
  // or at a restart).
  e.elapsed = static_cast<std::uint16_t>(std::max<std::int64_t>(0, now - e.start_ms));
  return force;
}

// PIDReportHandler::UppackUsbData: the report id picks the handler, byte 1 is the block.
void ArduinoFfb::output(std::span<const std::uint8_t> r) {
  if (r.size() < 2) return;
  const std::lock_guard lock(m_);
  outputs_.fetch_add(1);
  if (r[0] == id::kSetConstant) {
    constants_.fetch_add(1);
    last_constant_ms_ = now_ms();
    if (first_constant_ms_ < 0) first_constant_ms_ = last_constant_ms_;
  } else {
    note_command(r);
  }
  const std::uint8_t block = r[1];
  // The firmware indexes g_EffectStates with it unchecked; the reference ignores a wild one.
  Effect* e = block <= kMaxEffects ? &effects_[block] : nullptr;
  switch (r[0]) {
    case id::kSetEffect:
      set_effect(r);
      break;
    case id::kSetConstant:
      if (e != nullptr && r.size() >= 4) e->magnitude = static_cast<std::int16_t>(le16(r, 2));
      break;
    case id::kEffectOperation:
      effect_operation(r);
      break;
    case id::kBlockFree:  // 0xFF frees all; FreeEffect ignores an id past MAX_EFFECTS
      if (block == 0xFF) {
        device_control(4);
      } else if (e != nullptr) {
        e->state = 0;
        if (block < next_eid_) next_eid_ = block;
      }
      break;
    case id::kDeviceControl:
      device_control(block);
      break;
    default:  // Device Gain (kept, never used), envelope, condition, periodic, ramp, custom
      break;
  }
}

void ArduinoFfb::set_effect(std::span<const std::uint8_t> r) {
  // USB_FFBReport_SetEffect_Output_Data_t: id, block, type, duration, trigger repeat, sample
  // period (u16 each), gain, trigger button, enableAxis, directionX, directionY.
  if (r.size() < 14 || r[1] > kMaxEffects) return;
  Effect& e = effects_[r[1]];
  e.duration = le16(r, 3);
  e.dir_x = r[12];
  e.dir_y = r[13];
  e.type = r[2];
  e.gain = r[9];
  e.enable_axis = r[11];
}

void ArduinoFfb::effect_operation(std::span<const std::uint8_t> r) {
  if (r.size() < 4) return;
  const std::uint8_t block = r[1], op = r[2], loops = r[3];
  const auto start = [&](std::uint8_t b) {
    if (b > kMaxEffects) return;
    effects_[b].state = kPlaying;  // StartEffect: over ALLOCATED
    effects_[b].elapsed = 0;
    effects_[b].start_ms = now_ms();
  };
  if (op == 1) {
    if (block <= kMaxEffects && loops > 0) effects_[block].duration *= loops;
    if (block <= kMaxEffects && loops == 0xFF) effects_[block].duration = kInfinite;
    start(block);
  } else if (op == 2) {
    device_control(3);
    start(block);
  } else if (op == 3 && block <= kMaxEffects) {
    effects_[block].state &= static_cast<std::uint8_t>(~kPlaying);
    ram_available_ = static_cast<std::uint16_t>(ram_available_ + kEffectBytes);
  }
}

// PIDReportHandler::DeviceControl (the caller holds m_).
void ArduinoFfb::device_control(std::uint8_t control) {
  if (control == 1) status_ |= 2;  // Enable Actuators: a status bit, no force switched
  if (control == 2) status_ &= static_cast<std::uint8_t>(~2);
  if (control == 3) {  // StopAllEffects: every id 0..MAX_EFFECTS
    for (Effect& e : effects_) {
      e.state &= static_cast<std::uint8_t>(~kPlaying);
      ram_available_ = static_cast<std::uint16_t>(ram_available_ + kEffectBytes);
    }
  }
  if (control == 4) {  // FreeAllEffects
    next_eid_ = 1;
    for (Effect& e : effects_) e = Effect{};
    ram_available_ = kMaxEffects * kEffectBytes;
  }
  if (control == 5) paused_ = true;
  if (control == 6) paused_ = false;
}

// PIDReportHandler::GetNextFreeEffect (the caller holds m_).
std::uint8_t ArduinoFfb::next_free_effect() {
  if (next_eid_ == kMaxEffects) return 0;
  const std::uint8_t block = next_eid_++;
  while (effects_[next_eid_].state != 0) {
    if (next_eid_ >= kMaxEffects) break;  // the last spot was taken
    ++next_eid_;
  }
  effects_[block].state = kAllocated;
  return block;
}

// DynamicHID_::SetReport: feature 5 is Create New Effect; every other is taken and dropped.
bool ArduinoFfb::set_feature(std::span<const std::uint8_t> r) {
  if (r.empty()) return true;
  const std::lock_guard lock(m_);
  note_command(r);
  if (r[0] != id::kCreateNewEffect) return true;
  load_id_ = id::kBlockLoad;
  load_block_ = next_free_effect();
  load_status_ = load_block_ == 0 ? 2 : 1;  // 1 success, 2 full
  if (load_block_ != 0) {
    effects_[load_block_] = Effect{};
    effects_[load_block_].state = kAllocated;
    ram_available_ = static_cast<std::uint16_t>(ram_available_ - kEffectBytes);
  }
  return true;
}

// DynamicHID_::GetReport: Block Load's stored structure, whose reportId is then set to 0;
// the PID Pool built on the spot; nothing else (an empty answer).
std::optional<std::vector<std::uint8_t>> ArduinoFfb::get_feature(std::uint8_t i) {
  const std::lock_guard lock(m_);
  if (i == id::kBlockLoad) {
    block_load_reads_.fetch_add(1);
    std::vector<std::uint8_t> r{load_id_, load_block_, load_status_,
                                static_cast<std::uint8_t>(ram_available_ & 0xFF),
                                static_cast<std::uint8_t>(ram_available_ >> 8)};
    load_id_ = 0;
    return r;
  }
  if (i == id::kPidPool) return std::vector<std::uint8_t>{i, 0xFF, 0xFF, kMaxEffects, 3};
  return std::vector<std::uint8_t>{};
}

}  // namespace hapticd::reference
