// The `report` profile: vendor-defined reports in a configured layout (report_layout.h).

#include <array>

#include "base/errno_text.h"
#include "base/hex.h"
#include "drivers/device.h"
#include "drivers/hid/hid_profile.h"
#include "drivers/hid/report_descriptor.h"
#include "drivers/io/counter_unwrap.h"

namespace hapticd::drivers::hid {
namespace {

std::array<io::CounterUnwrap, base::kMaxJoints> make_unwraps(const InputLayout& in) {
  static_assert(base::kMaxJoints == 3, "one initial CounterUnwrap per joint");
  std::array<io::CounterUnwrap, base::kMaxJoints> u{{{8, false}, {8, false}, {8, false}}};
  for (std::size_t j = 0; j < in.joints() && j < u.size(); ++j) {
    u[j] = io::CounterUnwrap(static_cast<int>(in.joint(j).field.bits), in.joint(j).field.is_signed);
  }
  return u;
}

class ReportProfile final : public HidProfile {
 public:
  explicit ReportProfile(const HidSettings& s)
      : l_(s.report),
        timeout_(static_cast<long>(s.limits.timeout_ms)),
        out_(wire_size(l_.output.length)),
        off_(wire_size(l_.output.length)),
        unwrap_(make_unwraps(l_.input)) {
    prepare(out_, true);
    prepare(off_, false);
  }

  void configure(HidTransport& t) override {
    check_descriptor(t);
    if (l_.watchdog_feature) set(t, *l_.watchdog_feature, l_.watchdog_feature->on, "watchdog");
    send_now(t, off_, "the output-off report", timeout_);
    if (l_.enable_feature) set(t, *l_.enable_feature, l_.enable_feature->off, "enable (off)");
  }

  std::string summary() const override {
    return "report profile, input report " + std::to_string(l_.input.report_id) + " (" +
           std::to_string(l_.input.length) + " bytes), output report " +
           std::to_string(l_.output.report_id) + " (" + std::to_string(l_.output.length) +
           " bytes)" + descriptor_note_;
  }

  std::uint64_t sequence_modulus() const override {
    return l_.input.sequence ? counter_modulus(*l_.input.sequence) : 0;
  }

  void enable(HidTransport& t) override {
    if (l_.gain_feature) set(t, *l_.gain_feature, l_.gain_feature->on, "gain");
    if (l_.enable_feature) set(t, *l_.enable_feature, l_.enable_feature->on, "enable (on)");
    // Through force_report: the first enabled report moves the keep-alive on from the
    // output-off report before it, as every report after it does.
    send_now(t, force_report(kZeroForce), "the output-on report", timeout_);
  }

  void disable(HidTransport& t) noexcept override {
    if (!l_.enable_feature) return;
    try {
      set(t, *l_.enable_feature, l_.enable_feature->off, "enable (off)");
    } catch (const std::exception&) {
      // The safe report (output off, zero force) already went; the device is gone or stalls.
    }
  }

  std::vector<std::vector<std::uint8_t>> safe_reports() const override { return {off_}; }

  InputKind decode(std::span<const std::uint8_t> report, Decoded& d) noexcept override {
    const bool numbered = l_.input.report_id != 0;
    if ((!numbered || (!report.empty() && report[0] == l_.input.report_id)) &&
        report.size() > declared_input_ + (numbered ? 1 : 0)) {
      return InputKind::kTooLong;  // hidraw passes it whole: its fields cannot be trusted
    }
    InputValues v;
    switch (decode_input(report, l_.input, v)) {
      case InputDecode::kOk:
        break;
      case InputDecode::kOtherReport:
        return InputKind::kOther;
      default:
        return InputKind::kTooShort;
    }
    for (std::size_t j = 0; j < l_.input.joints(); ++j) {
      const PositionField p = l_.input.joint(j);
      d.position[j] = v.position[j];
      if (p.wraps) {  // a multi-turn axis: the count goes on past the field's ends
        const auto count = static_cast<std::uint64_t>(v.position_count[j]);
        d.position[j] =
            static_cast<double>(unwrap_[j].next(count)) * p.field.scale + p.field.offset;
      }
    }
    d.velocity = v.velocity;
    d.sequence = v.sequence;
    d.status = v.status;
    d.has_sequence = l_.input.sequence.has_value();
    d.has_velocity = l_.input.velocity.has_value();
    return InputKind::kPosition;
  }

  std::uint32_t fault_bits(std::uint32_t status) const noexcept override {
    return status & l_.input.fault_mask;
  }

  std::span<const std::uint8_t> before_force() noexcept override { return {}; }

  std::size_t joints() const noexcept override { return l_.input.joints(); }

  std::span<const std::span<const std::uint8_t>> force_reports(
      std::span<const double> forces) noexcept override {
    one_[0] = force_report(forces);
    return one_;
  }

  std::span<const std::uint8_t> force_report(std::span<const double> forces) noexcept {
    encode_force(forces, l_.output, out_);
    if (l_.output.keepalive) {  // a counter the firmware watches: it moves with every report
      const FieldSpec& k = *l_.output.keepalive;
      // 1, 2, ... M-1, 1...: never the output-off report's 0, so the report after it and
      // the one before it both differ from it.
      keepalive_ = keepalive_ % (counter_modulus(k) - 1) + 1;
      write_raw(out_.data() + 1, k, static_cast<double>(keepalive_));
    }
    return out_;
  }

  std::string describe_status(std::uint32_t status) const override {
    constexpr base::HexCase kLower = base::HexCase::kLower;
    return "status " + base::hex(status, 1, kLower) + " (fault bits " +
           base::hex(status & l_.input.fault_mask, 1, kLower) + " of mask " +
           base::hex(l_.input.fault_mask, 1, kLower) + ")";
  }

 private:
  void prepare(std::vector<std::uint8_t>& r, bool on) const {
    r[0] = l_.output.report_id;
    if (l_.output.enable) {
      const SwitchField& e = *l_.output.enable;
      write_raw(r.data() + 1, e.field, on ? e.on : e.off);
    }
    encode_force(kZeroForce, l_.output, r);
  }

  void set(HidTransport& t, const FeatureLayout& f, double raw, const char* what) {
    std::vector<std::uint8_t> r(wire_size(f.length));
    encode_feature(raw, f, r);
    try {
      t.set_feature(r);
    } catch (const DeviceError& e) {
      throw DeviceError(std::string("hid: setting the ") + what + " feature report " +
                        std::to_string(f.report_id) + ": " + e.what());
    }
  }

  // The configured layout against the device's own description of its reports, when it can
  // be read: a wrong report id or length is refused here, not discovered as garbage later.
  void check_descriptor(HidTransport& t) {
    std::vector<std::uint8_t> bytes;
    try {
      bytes = t.report_descriptor();
    } catch (const DeviceError& e) {
      descriptor_note_ = "; layout not checked against the device (" + std::string(e.what()) + ")";
      return;
    }
    const DescriptorParse p = parse_report_descriptor(bytes);
    if (!p.descriptor) {
      descriptor_note_ =
          "; layout not checked: the device's descriptor does not parse (" + p.error + ")";
      return;
    }
    need(*p.descriptor, ReportKind::kInput, l_.input.report_id, l_.input.length, "input");
    declared_input_ =
        p.descriptor->find_report(ReportKind::kInput, l_.input.report_id)->data_bytes();
    need(*p.descriptor, ReportKind::kOutput, l_.output.report_id, l_.output.length, "output");
    for (const auto* f : {&l_.enable_feature, &l_.gain_feature, &l_.watchdog_feature}) {
      if (*f) need(*p.descriptor, ReportKind::kFeature, (*f)->report_id, (*f)->length, "feature");
    }
  }

  static void need(const ParsedDescriptor& d, ReportKind kind, std::uint8_t id, std::size_t len,
                   const char* key) {
    const ReportInfo* r = d.find_report(kind, id);
    if (r == nullptr) {
      throw DeviceError(std::string("hid: the device has no ") + to_string(kind) + " report " +
                        std::to_string(id) + " (device.hid.report." + key + ".report_id)");
    }
    if (r->data_bytes() < len) {
      throw DeviceError(std::string("hid: the device's ") + to_string(kind) + " report " +
                        std::to_string(id) + " has " + std::to_string(r->data_bytes()) +
                        " data bytes, the layout needs " + std::to_string(len) +
                        " (device.hid.report." + key + ".length)");
    }
  }

  ReportProfileLayout l_;
  std::chrono::milliseconds timeout_;
  std::vector<std::uint8_t> out_;                     // the per-tick report, enable on
  std::array<std::span<const std::uint8_t>, 1> one_;  // force_reports(): out_
  std::vector<std::uint8_t> off_;                     // zero force, enable off
  std::uint64_t keepalive_ = 0;
  // Each wrapping joint's count since configure (unused for a joint that does not wrap).
  std::array<io::CounterUnwrap, base::kMaxJoints> unwrap_;
  std::string descriptor_note_;
  // The input report's length as the device declares it (the layout's when it has no
  // descriptor): anything longer is malformed.
  std::size_t declared_input_ = l_.input.length;
};

}  // namespace

std::unique_ptr<HidProfile> make_report_profile(const HidSettings& s) {
  return std::make_unique<ReportProfile>(s);
}

void send_now(HidTransport& t, std::span<const std::uint8_t> report, const std::string& what,
              std::chrono::milliseconds timeout) {
  IoResult r = t.write(report);
  if (r.status == TransportIo::kEmpty && t.flush(timeout)) r = t.write(report);
  if (r.status != TransportIo::kOk || !t.flush(timeout)) {
    const std::string why =
        r.status == TransportIo::kError ? base::errno_text(r.error)
        : r.status == TransportIo::kEmpty
            ? "the output queue stayed full"
            : "it was not taken within " + std::to_string(timeout.count()) + " ms";
    throw DeviceError("hid: sending " + what + ": " + why +
                      (t.last_error().empty() ? "" : " (" + t.last_error() + ")"));
  }
}

}  // namespace hapticd::drivers::hid
