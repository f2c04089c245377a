// The firmware of a force-feedback device on the HID PID page (profile pid): effect blocks
// created by feature report, Set Effect / Effect Operation / Device Control / Device Gain /
// Block Free, and the plant stepped by every Set Constant Force. It describes itself with
// pid_reference_descriptor() and finds its own fields in it with the driver's parser.
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>

#include "config/config_loader.h"
#include "drivers/hid/descriptor_builder.h"
#include "sim/peers/hid/hid_firmwares.h"

namespace hapticd::sim::hid {
namespace {

using namespace drivers::hid;

struct Effect {
  bool allocated = false, playing = false;
  std::int64_t magnitude = 0;
  double duration_ms = 0.0;   // 0: infinite
  std::uint64_t started = 0;  // plant step at Op Effect Start
  double gain = 1.0;
  std::array<double, 2> share{1.0, 0.0};  // each axis' torque per unit of magnitude
  bool fresh = false;                     // its Set Constant Force came since the last step
};

PidLayout own_layout(const std::vector<std::uint8_t>& descriptor, const config::Config& cfg,
                     const PidSettings& p) {
  const DescriptorParse parsed = parse_report_descriptor(descriptor);
  std::vector<std::uint32_t> usages;
  for (const PidPosition& pos : p.positions) usages.push_back(pos.usage);
  const PidFind f = find_pid_layout(*parsed.descriptor, usages, p.sequence_usage);
  if (!f.layout) {
    throw config::ConfigError({cfg.locate("device.hid.pid") +
                               ": device.hid.pid: the simulated PID device cannot serve this "
                               "configuration: " +
                               f.error});
  }
  return *f.layout;
}

class PidFirmware final : public HidFirmware {
 public:
  PidFirmware(const config::Config& cfg, const HidSettings& s, int link_delay,
              const PidFirmwareOptions& o)
      : HidFirmware(cfg, link_delay),
        p_(s.pid),
        o_(o),
        period_ms_(cfg.loop.sample_period_s() * 1e3),
        descriptor_(pid_reference_descriptor(
            {p_.sequence_usage == kReferenceSequenceUsage, true,
             o.sidewinder_lineage ? kSideWinderLineageIds : PidReferenceIds{},
             !o.sidewinder_lineage, static_cast<int>(s.pid.joints())})),
        l_(own_layout(descriptor_, cfg, p_)),
        pool_{o.sidewinder_lineage ? kSideWinderLineageIds.pool : PidReferenceIds{}.pool},
        position_(make_report(l_.position_report, l_.numbered)),
        state_(make_report(l_.state, l_.numbered)) {}

  const std::vector<std::uint8_t>& descriptor() const override { return descriptor_; }
  // A playing effect with a finite duration stops when it runs out: in wall time on a gadget,
  // where the plant does not step without the host.
  double watchdog_ms() const noexcept override {
    double ms = 0.0;
    for (const Effect& e : effects_) {
      if (e.playing && e.duration_ms > 0.0 && (ms == 0.0 || e.duration_ms < ms)) ms = e.duration_ms;
    }
    return ms;
  }

  void on_output(std::span<const std::uint8_t> r, const Send& send) override {
    if (is_report(r, l_.set_constant, l_.numbered)) {
      const auto d = data_of(r, l_.set_constant, l_.numbered);
      Effect* e = effect(get_slot(d, l_.sc_block));
      if (e != nullptr) e->magnitude = get_slot(d, l_.sc_magnitude);
      if (tick_complete(e) && amplifier_on()) {
        step(force());
        answer(send);
      }
    } else if (is_report(r, l_.set_effect, l_.numbered)) {
      set_effect(data_of(r, l_.set_effect, l_.numbered));
    } else if (is_report(r, l_.effect_operation, l_.numbered)) {
      const auto d = data_of(r, l_.effect_operation, l_.numbered);
      if (Effect* e = effect(get_slot(d, l_.eo_block))) {
        if (chosen(d, l_.eo_start)) e->started = plant().steps();
        e->playing = chosen(d, l_.eo_start) || (e->playing && !chosen(d, l_.eo_stop));
      }
    } else if (is_report(r, l_.device_control, l_.numbered)) {
      device_control(data_of(r, l_.device_control, l_.numbered), send);
    } else if (is_report(r, l_.device_gain, l_.numbered)) {
      const auto d = data_of(r, l_.device_gain, l_.numbered);
      device_gain_ = static_cast<double>(get_slot(d, l_.dg_gain)) /
                     static_cast<double>(l_.dg_gain.logical_max);
    } else if (is_report(r, l_.block_free, l_.numbered)) {
      if (Effect* e = effect(get_slot(data_of(r, l_.block_free, l_.numbered), l_.bf_block)))
        *e = {};
    }
    // The amplifier follows every change of what plays at once, not only at the next Set
    // Constant Force: a PID host (hid-pidff) sets the magnitude before it starts the effect.
    if (amplifier_on() && !is_report(r, l_.set_constant, l_.numbered)) hold(force());
    send_state(send);
  }

  int on_set_feature(std::span<const std::uint8_t> r, const Send&) override {
    if (!is_report(r, l_.create_effect, l_.numbered)) return EPIPE;
    load_status_ = l_.bl_error;
    load_block_ = 0;
    load_answered_ = false;
    if (chosen(data_of(r, l_.create_effect, l_.numbered), l_.ce_constant)) {
      load_status_ = l_.bl_full;
      for (std::size_t i = 0; i < effects_.size(); ++i) {
        if (effects_[i].allocated) continue;
        effects_[i] = {};
        effects_[i].allocated = true;
        load_block_ = static_cast<std::int64_t>(i) + 1;
        load_status_ = l_.bl_success;
        break;
      }
    }
    return 0;
  }

  int on_get_feature(std::uint8_t id, std::vector<std::uint8_t>& out) override {
    if (id == pool_.id) return pool_report(out);
    if (id != l_.block_load.id) return EPIPE;
    out = make_report(l_.block_load, l_.numbered);
    const auto d = data_of(std::span<std::uint8_t>(out), l_.block_load, l_.numbered);
    set_slot(d, l_.bl_block, load_block_);
    choose(d, load_status_);
    const auto used = std::count_if(effects_.begin(), effects_.end(),
                                    [](const Effect& e) { return e.allocated; });
    set_slot(d, l_.bl_ram_pool, static_cast<std::int64_t>(effects_.size()) - used);
    // The SideWinder lineage answers once: its stored report's id byte is 0 after that.
    if (o_.sidewinder_lineage && load_answered_) out[0] = 0;
    load_answered_ = true;
    return 0;
  }

  // PID Pool: as many effect blocks as it has, all playable at once, managed by the device.
  int pool_report(std::vector<std::uint8_t>& out) const {
    out.assign(pool_.size + 1, 0);
    out[0] = pool_.id;
    const std::uint16_t size = static_cast<std::uint16_t>(effects_.size() * sizeof(Effect));
    out[1] = static_cast<std::uint8_t>(size & 0xFF);
    out[2] = static_cast<std::uint8_t>(size >> 8);
    out[3] = static_cast<std::uint8_t>(effects_.size());
    out[4] = 0x01;  // Device Managed Pool 1, Shared Parameter Blocks 0
    return 0;
  }

  bool inject(PeerFault fault) noexcept override {
    if (fault == PeerFault::kSkipSequence && !l_.sequence.present) return false;
    return HidFirmware::inject(fault);
  }

 private:
  Effect* effect(std::int64_t block) {
    if (block < 1 || block > static_cast<std::int64_t>(effects_.size())) return nullptr;
    Effect& e = effects_[static_cast<std::size_t>(block - 1)];
    return e.allocated ? &e : nullptr;
  }

  // The host's tick has arrived with this Set Constant Force (of effect `e`): every playing
  // effect has its new magnitude (one effect per axis: one report each), or none plays, or `e`
  // had one already (a host that updates fewer effects than play, as hid-pidff may leave one
  // playing). Then the plant steps once a period, however many reports a tick carries.
  bool tick_complete(Effect* e) {
    const bool repeat = e != nullptr && e->fresh;
    if (e != nullptr) e->fresh = true;
    const bool all = repeat || std::all_of(effects_.begin(), effects_.end(),
                                           [](const Effect& x) { return !x.playing || x.fresh; });
    if (all) {
      for (Effect& x : effects_) x.fresh = false;
    }
    return all;
  }

  void set_effect(std::span<const std::uint8_t> d) {
    Effect* e = effect(get_slot(d, l_.se_block));
    if (e == nullptr) return;
    const std::int64_t dur = get_slot(d, l_.se_duration);
    const Slot& ds = l_.se_duration;
    e->duration_ms = !ds.present || dur < ds.logical_min || dur > ds.logical_max
                         ? 0.0  // the null value: infinite
                         : static_cast<double>(dur);
    if (l_.se_gain.present) {
      e->gain = static_cast<double>(get_slot(d, l_.se_gain)) /
                static_cast<double>(l_.se_gain.logical_max);
    }
    set_shares(d, *e);
  }

  // Which way each axis turns a positive magnitude, as OpenFFBoard's HidFFB.cpp set_effect
  // reads the Set Effect (docs/drivers/hid.md, "Two axes"): with Direction Enable (or on a
  // device of one axis) DirectInput's polar direction, where the force comes from,
  // -magnitude * sin on X and +cos on Y (EffectsCalculator.cpp: torque = -magnitude * share);
  // the SideWinder lineage's +sin (ArduinoJoystickWithFFBLibrary, getEffectForce) the reverse.
  // Without it, each enabled axis reads its own Direction linearly, (d - mid) / half of its
  // range on X and the negative on Y; an axis not enabled gets nothing.
  void set_shares(std::span<const std::uint8_t> d, Effect& e) const {
    const Slot& dir = l_.se_direction;
    if (!dir.present) return;
    const bool polar = p_.joints() == 1 || get_slot(d, l_.se_direction_enable) != 0;
    if (polar) {
      const double turn = static_cast<double>(dir.logical_max - dir.logical_min + 1);
      const double angle =
          2.0 * M_PI * static_cast<double>(get_slot(d, dir) - dir.logical_min) / turn;
      e.share = {(o_.sidewinder_lineage ? 1.0 : -1.0) * std::sin(angle), std::cos(angle)};
      return;
    }
    const auto linear = [&](const Slot& s, const Slot& enable) {
      if (get_slot(d, enable) == 0) return 0.0;
      const double mid = static_cast<double>(s.logical_min + s.logical_max) / 2.0;
      const double half = static_cast<double>(s.logical_max - s.logical_min) / 2.0;
      return (static_cast<double>(get_slot(d, s)) - mid) / half;
    };
    e.share = {-linear(dir, l_.se_axis_x), linear(l_.se_direction_y, l_.se_axis_y)};
  }

  void device_control(std::span<const std::uint8_t> d, const Send& send) {
    if (chosen(d, l_.dc_stop_all) || chosen(d, l_.dc_reset)) {
      for (Effect& e : effects_) e.playing = false;
    }
    if (chosen(d, l_.dc_reset)) effects_.fill({});
    if (chosen(d, l_.dc_disable) || chosen(d, l_.dc_reset)) set_output(false);
    if (chosen(d, l_.dc_enable) && !amplifier_on() && !device_fault()) {
      set_output(true);
      send_state(send);
      answer(send);  // enabled: report the state at rest
    }
  }

  // Each joint's force of every playing effect, as the amplifier makes it.
  std::span<const double> force() {
    forces_ = {};
    if (device_fault()) return std::span<const double>(forces_.data(), joints());
    for (Effect& e : effects_) {
      if (e.playing && e.duration_ms > 0.0 &&
          static_cast<double>(plant().steps() - e.started) * period_ms_ >= e.duration_ms) {
        e.playing = false;  // ran out: the firmware's own watchdog
      }
      if (!e.playing) continue;
      const double level = static_cast<double>(e.magnitude) /
                           static_cast<double>(l_.sc_magnitude.logical_max) * p_.force_full_scale *
                           e.gain * device_gain_;
      for (std::size_t j = 0; j < joints(); ++j) forces_[j] += level * e.share[j];
    }
    return std::span<const double>(forces_.data(), joints());
  }

  void answer(const Send& send) {
    if (!answering()) return;
    const auto d = data_of(std::span<std::uint8_t>(position_), l_.position_report, l_.numbered);
    for (std::size_t j = 0; j < joints(); ++j) {
      const Slot& s = l_.positions[j];
      const PidPosition& p = p_.positions[j];
      const double span = static_cast<double>(s.logical_max - s.logical_min);
      const double raw = static_cast<double>(s.logical_min) +
                         (measured_position(j) - p.min) / (p.max - p.min) * span;
      set_slot(d, s,
               static_cast<std::int64_t>(std::clamp(std::nearbyint(raw),
                                                    static_cast<double>(s.logical_min),
                                                    static_cast<double>(s.logical_max))));
    }
    if (l_.sequence.present) set_slot(d, l_.sequence, next_sequence());
    send(position_);
  }

  void send_state(const Send& send) {
    // The SideWinder lineage declares PID State and never sends it.
    if (!l_.state.present || !answering() || o_.sidewinder_lineage) return;
    const bool playing =
        std::any_of(effects_.begin(), effects_.end(), [](const Effect& e) { return e.playing; });
    const auto d = data_of(std::span<std::uint8_t>(state_), l_.state, l_.numbered);
    // A faulted device turns its actuators off, and says why where it can: its safety switch.
    set_slot(d, l_.st_actuators_enabled, amplifier_on() && !device_fault() ? 1 : 0);
    set_slot(d, l_.st_safety_switch, device_fault() ? 0 : 1);
    set_slot(d, l_.st_power, 1);
    set_slot(d, l_.st_playing, playing ? 1 : 0);
    if (state_ == sent_state_) return;  // only changes are reported
    sent_state_ = state_;
    send(state_);
  }

  // The PID Pool feature report of pid_reference_descriptor(): not one the profile reads.
  struct PoolRef {
    std::uint8_t id = PidReferenceIds{}.pool;
    std::size_t size = 4;  // RAM Pool Size u16, Simultaneous Effects Max u8, two flags + pad
  };
  PidSettings p_;
  PidFirmwareOptions o_;
  double period_ms_;
  std::vector<std::uint8_t> descriptor_;
  PidLayout l_;
  PoolRef pool_;
  std::vector<std::uint8_t> position_, state_, sent_state_;
  std::array<Effect, 8> effects_{};
  std::array<double, 2> forces_{};  // force()'s
  double device_gain_ = 1.0;
  Choice load_status_;
  std::int64_t load_block_ = 0;
  bool load_answered_ = false;  // Block Load read since the last Create New Effect
};

}  // namespace

std::unique_ptr<HidFirmware> make_pid_firmware(const config::Config& cfg,
                                               const drivers::hid::HidSettings& s, int link_delay,
                                               const PidFirmwareOptions& options) {
  return std::make_unique<PidFirmware>(cfg, s, link_delay, options);
}

std::unique_ptr<HidFirmware> make_firmware(const config::Config& cfg, int link_delay) {
  const auto* s = dynamic_cast<const drivers::hid::HidSettings*>(cfg.device.settings.get());
  if (s == nullptr) throw std::logic_error("make_firmware: the configuration has no device.hid");
  return s->profile == drivers::hid::Profile::kReport ? make_report_firmware(cfg, *s, link_delay)
                                                      : make_pid_firmware(cfg, *s, link_delay);
}

}  // namespace hapticd::sim::hid
