// The `pid` profile: constant-force effects on the HID PID page (pid_protocol.h), their reports
// found in the device's report descriptor. One joint: one effect with a polar Direction. Two:
// one effect per axis, each selecting its own axis (Axes Enable X, then Y) with Direction Enable
// clear and its own Direction, so a tick sends one Set Constant Force per joint and never a Set
// Effect (docs/drivers/hid.md, "Two axes").
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/hex.h"
#include "drivers/device.h"
#include "drivers/hid/hid_profile.h"

namespace hapticd::drivers::hid {
namespace {

class PidProfile final : public HidProfile {
 public:
  PidProfile(const HidSettings& s, double period_s)
      : s_(s.pid), timeout_(static_cast<long>(s.limits.timeout_ms)), effects_(s.pid.joints()) {
    if (s_.effect_duration_ms > 0.0) {
      // Each effect restarted every half duration, one a tick in turn (the configuration makes
      // that at least one tick per effect); a restart the full OUT queue could not take goes at
      // the next tick that can (HidDevice::on_write), so an effect runs out only if nothing is
      // written for half its duration.
      refresh_ticks_ = std::max<std::uint64_t>(
          effects_.size(), static_cast<std::uint64_t>(s_.effect_duration_ms / 2e3 / period_s));
    }
  }

  void configure(HidTransport& t) override {
    const std::vector<std::uint8_t> bytes = t.report_descriptor();
    const DescriptorParse p = parse_report_descriptor(bytes);
    if (!p.descriptor) throw DeviceError("hid: the device's report descriptor: " + p.error);
    std::vector<std::uint32_t> usages;
    for (const PidPosition& pos : s_.positions) usages.push_back(pos.usage);
    PidFind f = find_pid_layout(*p.descriptor, usages, s_.sequence_usage);
    if (!f.layout) throw DeviceError("hid: this device cannot run the pid profile: " + f.error);
    l_ = *f.layout;
    prepare();
    send_now(t, stop_all_, "Device Control (stop all effects)", timeout_);
    send_now(t, disable_, "Device Control (disable actuators)", timeout_);
  }

  std::string summary() const override {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "pid profile, %s, Set Constant Force report %u, position%s in input report %u%s",
                  effects_.size() == 1 ? "one effect" : "one effect per axis (X, Y)",
                  l_.set_constant.id, effects_.size() == 1 ? "" : "s", l_.position_report.id,
                  l_.state.present ? ", PID State report" : "");
    return buf;
  }

  std::uint64_t sequence_modulus() const override {
    return l_.sequence.present && !l_.sequence.is_signed ? std::uint64_t{1} << l_.sequence.bit_size
                                                         : 0;
  }

  void enable(HidTransport& t) override {
    freed_every_block_ = false;
    for (Effect& e : effects_) e.block = create_effect(t);
    set_block_everywhere();
    for (std::size_t j = 0; j < effects_.size(); ++j) {
      std::vector<std::uint8_t> effect = make_report(l_.set_effect, l_.numbered);
      fill_set_effect(data(effect, l_.set_effect), j);
      send_now(t, effect, "Set Effect", timeout_);
    }
    for (const std::span<const std::uint8_t> r : force_reports(kZeroForce)) {
      send_now(t, r, "Set Constant Force", timeout_);
    }
    if (l_.device_gain.present) {
      std::vector<std::uint8_t> gain = make_report(l_.device_gain, l_.numbered);
      set_slot(data(gain, l_.device_gain), l_.dg_gain,
               std::llround(s_.gain * static_cast<double>(l_.dg_gain.logical_max)));
      send_now(t, gain, "Device Gain", timeout_);
    }
    for (const Effect& e : effects_) send_now(t, e.start, "Effect Operation (start)", timeout_);
    confirmed_ = false;
    send_now(t, enable_, "Device Control (enable actuators)", timeout_);
    ticks_ = 0;
  }

  void disable(HidTransport& t) noexcept override {
    for (Effect& e : effects_) {
      if (e.block == 0 || !l_.block_free.present) continue;
      std::vector<std::uint8_t> free = make_report(l_.block_free, l_.numbered);
      set_slot(data(free, l_.block_free), l_.bf_block, e.block);
      try {
        send_now(t, free, "Block Free", timeout_);
      } catch (const std::exception&) {
        // Effects are stopped and actuators off already; a device that is gone frees it anyway.
      }
      e.block = 0;
    }
  }

  std::vector<std::vector<std::uint8_t>> safe_reports() const override {
    std::vector<std::vector<std::uint8_t>> out;
    for (const Effect& e : effects_) {
      std::vector<std::uint8_t> zero = e.constant;
      set_slot(data(zero, l_.set_constant), l_.sc_magnitude, 0);
      out.push_back(std::move(zero));
    }
    out.push_back(stop_all_);
    out.push_back(disable_);
    return out;
  }

  InputKind decode(std::span<const std::uint8_t> report, Decoded& d) noexcept override {
    if (longer_than_declared(report, l_.position_report) || longer_than_declared(report, l_.state))
      return InputKind::kTooLong;
    if (is_report(report, l_.position_report, l_.numbered)) {
      const auto in = data_of(report, l_.position_report, l_.numbered);
      for (std::size_t j = 0; j < effects_.size(); ++j) {
        const Slot& p = l_.positions[j];
        const double raw = static_cast<double>(get_slot(in, p));
        d.position[j] = s_.positions[j].min +
                        (raw - static_cast<double>(p.logical_min)) * effects_[j].position_scale;
      }
      d.has_sequence = l_.sequence.present;
      if (d.has_sequence) d.sequence = static_cast<std::uint32_t>(get_slot(in, l_.sequence));
      return InputKind::kPosition;
    }
    if (l_.state.present && is_report(report, l_.state, l_.numbered)) {
      d.status = pid_status(data_of(report, l_.state, l_.numbered), l_);
      confirmed_ = confirmed_ || (d.status & kPidActuatorsDisabled) == 0;
      return InputKind::kState;
    }
    const bool ours =
        !report.empty() && l_.numbered &&
        (report[0] == l_.position_report.id || (l_.state.present && report[0] == l_.state.id));
    return ours ? InputKind::kTooShort : InputKind::kOther;
  }

  // "Actuators disabled" counts only once the device has reported them enabled: a state
  // report sent before it handled the enable (still on its way at the first tick) is history.
  std::uint32_t fault_bits(std::uint32_t status) const noexcept override {
    return status & s_.fault_mask & (confirmed_ ? ~0u : ~std::uint32_t{kPidActuatorsDisabled});
  }

  // Restarts the finite effects before they run out: effect j j ticks before every refresh
  // tick (effect 0 at it), so none waits longer than half its duration.
  std::span<const std::uint8_t> before_force() noexcept override {
    if (refresh_ticks_ == 0) return {};
    const std::uint64_t phase = ++ticks_ % refresh_ticks_;
    const std::uint64_t j = (refresh_ticks_ - phase) % refresh_ticks_;
    return j < effects_.size() ? std::span<const std::uint8_t>(effects_[j].start)
                               : std::span<const std::uint8_t>();
  }

  std::size_t joints() const noexcept override { return effects_.size(); }

  std::span<const std::span<const std::uint8_t>> force_reports(
      std::span<const double> forces) noexcept override {
    const Slot& m = l_.sc_magnitude;
    for (std::size_t j = 0; j < effects_.size(); ++j) {
      const double raw = std::nearbyint(forces[j] * counts_per_force_);
      const double clamped =
          std::clamp(raw, static_cast<double>(m.logical_min), static_cast<double>(m.logical_max));
      set_slot(data(effects_[j].constant, l_.set_constant), m, static_cast<std::int64_t>(clamped));
    }
    return std::span<const std::span<const std::uint8_t>>(reports_.data(), effects_.size());
  }

  std::string describe_status(std::uint32_t status) const override {
    static const char* const kNames[] = {"paused",
                                         "actuators disabled",
                                         "safety switch off",
                                         "actuator override",
                                         "actuator power off",
                                         "effect not playing"};
    std::string s;
    for (unsigned i = 0; i < 6; ++i) {
      if (status & (1u << i)) s += (s.empty() ? "" : ", ") + std::string(kNames[i]);
    }
    return "the device reports " + (s.empty() ? std::string("nothing wrong") : s) +
           " (PID State bits " + base::hex(status, 1, base::HexCase::kLower) + ", fault mask " +
           base::hex(s_.fault_mask, 1, base::HexCase::kLower) + ")";
  }

 private:
  // Our id (or the device's one unnumbered report) with more bytes than the descriptor gives
  // it: hidraw hands such a report over whole, and its fields cannot be trusted.
  bool longer_than_declared(std::span<const std::uint8_t> r, const ReportRef& ref) const noexcept {
    if (!ref.present || (l_.numbered && (r.empty() || r[0] != ref.id))) return false;
    return r.size() > ref.data_bytes + (l_.numbered ? 1 : 0);
  }

  std::span<std::uint8_t> data(std::vector<std::uint8_t>& r, const ReportRef& ref) const {
    return data_of(std::span<std::uint8_t>(r), ref, l_.numbered);
  }

  void prepare() {
    counts_per_force_ = static_cast<double>(l_.sc_magnitude.logical_max) / s_.force_full_scale;
    for (std::size_t j = 0; j < effects_.size(); ++j) {
      const Slot& p = l_.positions[j];
      Effect& e = effects_[j];
      e.position_scale =
          (s_.positions[j].max - s_.positions[j].min) /
          static_cast<double>(std::max<std::int64_t>(1, p.logical_max - p.logical_min));
      e.constant = make_report(l_.set_constant, l_.numbered);
      e.start = make_report(l_.effect_operation, l_.numbered);
      choose(data(e.start, l_.effect_operation), l_.eo_start);
      set_slot(data(e.start, l_.effect_operation), l_.eo_loop_count, 1);
      reports_[j] = e.constant;  // the vectors keep their buffers from here on
    }
    stop_all_ = make_report(l_.device_control, l_.numbered);
    choose(data(stop_all_, l_.device_control), l_.dc_stop_all);
    disable_ = make_report(l_.device_control, l_.numbered);
    choose(data(disable_, l_.device_control), l_.dc_disable);
    enable_ = make_report(l_.device_control, l_.numbered);
    choose(data(enable_, l_.device_control), l_.dc_enable);
  }

  // Create New Effect and its Block Load: the block index the device gave the effect.
  std::int64_t create_effect(HidTransport& t) {
    std::vector<std::uint8_t> create = make_report(l_.create_effect, l_.numbered);
    choose(data(create, l_.create_effect), l_.ce_constant);
    t.set_feature(create);
    LoadAnswer a = read_block_load(t);
    if (a.full && l_.block_free.present && !freed_every_block_) {
      // A run that ended without its own code running (SIGKILL, power cut of the host) left
      // its blocks allocated; blocks are indexed, so free them all and ask once more. hapticd
      // is the device's only user while it runs (docs/drivers/hid.md). Only before this
      // enable allocated any: freeing then would free its own.
      free_every_block(t);
      t.set_feature(create);
      a = read_block_load(t);
    }
    if (a.full && freed_every_block_) {  // an effect of this enable holds a block already
      throw DeviceError(
          "hid: Block Load after Create New Effect: the device's effect memory is "
          "full with this run's first effect in it: it cannot hold the " +
          std::to_string(effects_.size()) +
          " effects (one per axis) the pid profile of two axes needs");
    }
    freed_every_block_ = true;
    if (!a.error.empty()) throw DeviceError("hid: Block Load after Create New Effect: " + a.error);
    return a.block;
  }

  struct LoadAnswer {
    std::int64_t block = 0;
    bool full = false;
    std::string error;  // empty on success
  };

  // Block Load, read back after Create New Effect: the index the device gave the effect.
  LoadAnswer read_block_load(HidTransport& t) {
    const std::vector<std::uint8_t> r = t.get_feature(l_.block_load.id, l_.block_load.wire_size());
    if (r.size() < l_.block_load.wire_size() || r[0] != l_.block_load.id) {
      throw DeviceError("hid: Block Load: the device answered " + std::to_string(r.size()) +
                        " bytes with report id " + std::to_string(r.empty() ? 0 : r[0]) +
                        ", not feature report " + std::to_string(l_.block_load.id));
    }
    const auto in = data_of(std::span<const std::uint8_t>(r), l_.block_load, l_.numbered);
    LoadAnswer a;
    a.block = get_slot(in, l_.bl_block);
    if (chosen(in, l_.bl_success) &&
        a.block >= std::max<std::int64_t>(1, l_.bl_block.logical_min) &&
        a.block <= l_.bl_block.logical_max) {
      return a;
    }
    a.full = chosen(in, l_.bl_full);
    a.error =
        a.full                    ? "the device's effect memory is full"
        : chosen(in, l_.bl_error) ? "the device reports a load error"
        : chosen(in, l_.bl_success)
            ? "success, but effect block index " + std::to_string(a.block) + " is outside its range"
            : "status " + std::to_string(get_slot(in, l_.bl_success.slot)) +
                  " is none of success, full, error";
    if (l_.bl_ram_pool.present)
      a.error += " (RAM pool available " + std::to_string(get_slot(in, l_.bl_ram_pool)) + ")";
    if (a.full) {
      a.error += l_.block_free.present
                     ? ", even after Block Free of every index " + block_range() +
                           ": power-cycle the device (unplug it and plug it in again)"
                     : "; it has no Block Free report: power-cycle the device (unplug it and "
                       "plug it in again)";
    }
    return a;
  }

  std::string block_range() const {
    return std::to_string(std::max<std::int64_t>(1, l_.bf_block.logical_min)) + ".." +
           std::to_string(std::min<std::int64_t>(255, l_.bf_block.logical_max));
  }

  void free_every_block(HidTransport& t) {
    std::vector<std::uint8_t> free = make_report(l_.block_free, l_.numbered);
    const std::int64_t last = std::min<std::int64_t>(255, l_.bf_block.logical_max);
    for (std::int64_t i = std::max<std::int64_t>(1, l_.bf_block.logical_min); i <= last; ++i) {
      set_slot(data(free, l_.block_free), l_.bf_block, i);
      send_now(t, free, "Block Free " + std::to_string(i), timeout_);
    }
    spdlog::warn(
        "hid: the device's effect memory was full (a run before this one could not free its "
        "block): freed every block index {}",
        block_range());
  }

  void fill_set_effect(std::span<std::uint8_t> d, std::size_t joint) const {
    set_slot(d, l_.se_block, effects_[joint].block);
    choose(d, l_.se_constant);
    const std::int64_t duration = s_.effect_duration_ms > 0.0 ? std::llround(s_.effect_duration_ms)
                                                              : null_value(l_.se_duration);
    set_slot(d, l_.se_duration, duration);  // null: infinite
    set_slot(d, l_.se_gain, l_.se_gain.logical_max);
    set_slot(d, l_.se_trigger_button, null_value(l_.se_trigger_button));
    if (effects_.size() == 1) {
      set_slot(d, l_.se_axis_x, 1);
      set_slot(d, l_.se_direction_enable, 1);
      // The Direction's logical range is one full turn (0..35999 hundredths of a degree,
      // 0..255...), polar as DirectInput has it: where the force comes from
      // (docs/drivers/hid.md).
      const Slot& dir = l_.se_direction;
      if (dir.present) {
        const double turn = static_cast<double>(dir.logical_max - dir.logical_min + 1);
        set_slot(d, dir, dir.logical_min + std::llround(s_.direction_deg / 360.0 * turn));
      }
      return;
    }
    // Two joints: this effect acts on its own axis only, with its own Direction instance,
    // 0..360 degrees onto the whole logical range (OpenFFBoard's 0..36000 exactly).
    set_slot(d, l_.se_axis_x, joint == 0 ? 1 : 0);
    set_slot(d, l_.se_axis_y, joint == 1 ? 1 : 0);
    set_slot(d, l_.se_direction_enable, 0);
    const Slot& dir = joint == 0 ? l_.se_direction : l_.se_direction_y;
    set_slot(d, dir, direction_value(dir, s_.directions_deg[joint]));
  }

  void set_block_everywhere() {
    for (Effect& e : effects_) {
      set_slot(data(e.constant, l_.set_constant), l_.sc_block, e.block);
      set_slot(data(e.start, l_.effect_operation), l_.eo_block, e.block);
    }
  }

  PidSettings s_;
  std::chrono::milliseconds timeout_;
  PidLayout l_;
  // One effect per joint: its block, its reports, and its joint's position scale.
  struct Effect {
    std::int64_t block = 0;
    double position_scale = 0.0;
    std::vector<std::uint8_t> constant, start;
  };
  std::vector<Effect> effects_;
  std::array<std::span<const std::uint8_t>, base::kMaxJoints> reports_{};  // each constant
  bool confirmed_ = false;  // a state report with the actuators enabled arrived since enable
  std::uint64_t refresh_ticks_ = 0, ticks_ = 0;
  bool freed_every_block_ = false;  // this enable has freed the pool once
  double counts_per_force_ = 0.0;   // Magnitude counts per N (N m): its maximum at full scale
  std::vector<std::uint8_t> stop_all_, disable_, enable_;
};

}  // namespace

std::unique_ptr<HidProfile> make_pid_profile(const HidSettings& s, double sample_period_s) {
  return std::make_unique<PidProfile>(s, sample_period_s);
}

}  // namespace hapticd::drivers::hid
