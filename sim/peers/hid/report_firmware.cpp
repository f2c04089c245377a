// The firmware of a device with vendor-defined reports (profile report): it decodes the output
// report with the configured layout and answers with the input report.
#include <cerrno>
#include <map>
#include <stdexcept>
#include <string>

#include "drivers/hid/descriptor_builder.h"
#include "sim/peers/hid/hid_firmware.h"
#include "sim/peers/hid/hid_firmwares.h"

namespace hapticd::sim::hid {
namespace {

using namespace drivers::hid;

// The simulated firmware's own watchdog when the host does not configure one (ms).
constexpr double kDefaultWatchdogMs = 100.0;

// The layout's joints are the mechanism's (the configuration checks it; a test may not).
const ReportProfileLayout& checked_joints(const ReportProfileLayout& l, std::size_t joints) {
  if (l.input.joints() != joints || l.output.joints() != joints) {
    throw std::invalid_argument("hid report firmware: the layout has " +
                                std::to_string(l.input.joints()) + " position and " +
                                std::to_string(l.output.joints()) + " force field(s) for " +
                                std::to_string(joints) + " joint(s)");
  }
  return l;
}

class ReportFirmware final : public HidFirmware {
 public:
  ReportFirmware(const config::Config& cfg, const HidSettings& s, int link_delay)
      : HidFirmware(cfg, link_delay),
        l_(checked_joints(s.report, joints())),
        descriptor_(report_profile_descriptor(l_)),
        answer_(input_report_size(l_.input)),
        feature_on_(!l_.enable_feature),
        watchdog_ms_(kDefaultWatchdogMs) {}

  const std::vector<std::uint8_t>& descriptor() const override { return descriptor_; }
  double watchdog_ms() const noexcept override { return watchdog_ms_; }

  void on_output(std::span<const std::uint8_t> report, const Send& send) override {
    OutputValues v;
    if (!decode_output(report, l_.output, v)) return;  // not ours: firmware ignores it
    field_on_ = v.enable;
    const bool was_on = amplifier_on();
    // A keep-alive that stopped moving is a host that is stuck: no force this period.
    const bool stuck = l_.output.keepalive && have_keepalive_ && v.keepalive == keepalive_;
    keepalive_ = v.keepalive;
    have_keepalive_ = true;
    if (!update_output()) return;
    if (!was_on) {
      answer(send);  // enabled: report the state at rest
      return;
    }
    if (device_fault() || stuck) v.force = {};
    step(std::span<const double>(v.force.data(), joints()));
    answer(send);
  }

  int on_set_feature(std::span<const std::uint8_t> report, const Send& send) override {
    if (report.empty()) return EPIPE;
    features_[report[0]].assign(report.begin(), report.end());
    if (l_.watchdog_feature) {
      if (const auto v = decode_feature(report, *l_.watchdog_feature)) watchdog_ms_ = *v;
    }
    if (l_.enable_feature && report[0] == l_.enable_feature->report_id) {
      const auto v = decode_feature(report, *l_.enable_feature);
      if (!v) return EPIPE;
      const bool was_on = amplifier_on();
      feature_on_ = *v == l_.enable_feature->on;
      if (update_output() && !was_on) answer(send);
      return 0;
    }
    const bool known = (l_.gain_feature && report[0] == l_.gain_feature->report_id) ||
                       (l_.watchdog_feature && report[0] == l_.watchdog_feature->report_id);
    return known ? 0 : EPIPE;
  }

  int on_get_feature(std::uint8_t id, std::vector<std::uint8_t>& out) override {
    const auto it = features_.find(id);
    if (it == features_.end()) return EPIPE;
    out = it->second;
    return 0;
  }

  bool inject(PeerFault fault) noexcept override {
    if (fault == PeerFault::kSkipSequence && !l_.input.sequence) return false;
    if (fault == PeerFault::kDeviceFault && (!l_.input.status || l_.input.fault_mask == 0)) {
      return false;
    }
    return HidFirmware::inject(fault);
  }

 private:
  // The amplifier follows the enable field and the enable feature; true while it is on.
  bool update_output() {
    const bool on = field_on_ && feature_on_;
    if (on != amplifier_on()) set_output(on);
    return on;
  }

  void answer(const Send& send) {
    if (!answering()) return;
    InputValues v;
    for (std::size_t j = 0; j < joints(); ++j) v.position[j] = measured_position(j);
    v.velocity = velocity();
    v.sequence = next_sequence();
    if (device_fault()) {
      const std::uint32_t mask = l_.input.fault_mask;
      v.status = mask & (~mask + 1);  // the lowest fault bit
    }
    encode_input(v, l_.input, answer_);
    send(answer_);
  }

  ReportProfileLayout l_;
  std::vector<std::uint8_t> descriptor_;
  std::vector<std::uint8_t> answer_;
  std::map<std::uint8_t, std::vector<std::uint8_t>> features_;
  bool field_on_ = false;
  bool feature_on_;
  double keepalive_ = 0.0;
  bool have_keepalive_ = false;
  double watchdog_ms_;
};

}  // namespace

std::unique_ptr<HidFirmware> make_report_firmware(const config::Config& cfg,
                                                  const drivers::hid::HidSettings& s,
                                                  int link_delay) {
  return std::make_unique<ReportFirmware>(cfg, s, link_delay);
}

}  // namespace hapticd::sim::hid
