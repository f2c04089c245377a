// libFuzzer target for the HID driver's pure codecs (drivers/hid/). Byte 0 & 3 says what the
// rest of the input is:
//   0  a report descriptor: its parse keeps report_descriptor.h's promises or names the byte it
//      refuses; the PID layout found in it (bit 2 of byte 0: with the reference sequence usage)
//      is written and read back slot by slot, in reports filled with the descriptor's bytes;
//   1  a `report` layout (layout() below), max_force, values and reports: what validate()
//      accepts must round-trip through the codecs, and any report decode as documented;
//   2  a loopback message: what parse_frame accepts re-frames to the same bytes;
//   3  an offset, a width and a value for get_bits/put_bits over the tail, against a model.
#include <algorithm>
#include <bit>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/hid_framing.h"
#include "drivers/hid/pid_protocol.h"
#include "drivers/hid/report_descriptor.h"
#include "drivers/hid/report_layout.h"
#include "support/check.h"

namespace {

namespace hid = hapticd::drivers::hid;
using hapticd::fuzz::require;
using Bytes = std::vector<std::uint8_t>;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTiny = std::numeric_limits<double>::denorm_min();
constexpr double kFloatMax = static_cast<double>(FLT_MAX);

// The input read front to back; past its end every read is 0, so any input is a whole case.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> b) : b_(b) {}
  std::uint8_t u8() { return at_ < b_.size() ? b_[at_++] : 0; }
  // Separate statements: the operands of | are unsequenced.
  std::uint16_t u16() {
    const unsigned lo = u8();
    return static_cast<std::uint16_t>(lo | unsigned{u8()} << 8);
  }
  std::uint32_t u32() {
    const std::uint32_t lo = u16();
    return lo | std::uint32_t{u16()} << 16;
  }
  // A value from the table (the edges the codecs clamp, round or refuse), or any double.
  double number() {
    static constexpr double kNumbers[] = {
        0.0,    1.0,    -1.0,  0.5,     1.5,       2.5,     10.0,    1e-3, -1e-3,        1e-5,
        127.0,  127.5,  255.0, 1e4,     10000.5,   32767.0, 65535.0, 1e9,  4294967295.0, 1e300,
        -1e300, 1e-300, kTiny, DBL_MAX, kFloatMax, 0.1,     -0.0,    kNaN, kInf,         -kInf};
    const std::uint8_t s = u8();
    if (s < 0xF0) return kNumbers[s % std::size(kNumbers)];
    const std::uint64_t lo = u32();
    return std::bit_cast<double>(lo | std::uint64_t{u32()} << 32);
  }
  // Type byte: bits 0-2 the type (mod 7), 3 big-endian, 4 a 16-bit offset, 5 a scale, 6 an
  // offset in SI units.
  hid::FieldSpec field() {
    const std::uint8_t t = u8();
    hid::FieldSpec f;
    f.type = static_cast<hid::FieldType>((t & 7u) % 7u);
    f.endian = (t & 8u) != 0 ? hid::Endian::kBig : hid::Endian::kLittle;
    f.byte = (t & 16u) != 0 ? u16() : u8();
    if ((t & 32u) != 0) f.scale = number();
    if ((t & 64u) != 0) f.offset = number();
    return f;
  }
  // 0xFF: a 16-bit length follows (past kMaxReportData, which validate refuses).
  std::size_t length() {
    const std::uint8_t n = u8();
    return n == 0xFF ? u16() : n;
  }
  std::optional<hid::FeatureLayout> feature(bool present) {
    if (!present) return std::nullopt;
    return hid::FeatureLayout{u8(), length(), field(), number(), number()};  // in this order
  }
  std::span<const std::uint8_t> rest() const { return b_.subspan(std::min(at_, b_.size())); }

 private:
  std::span<const std::uint8_t> b_;
  std::size_t at_ = 0;
};

// Byte 0 says which optional parts follow, in the order of report_layout.h's structs.
hid::ReportProfileLayout layout(Reader& r) {
  const std::uint8_t has = r.u8();
  hid::ReportProfileLayout l;
  l.input.report_id = r.u8();
  l.input.length = r.length();
  l.input.position = r.field();
  if ((has & 1u) != 0) l.input.sequence = r.field();
  if ((has & 2u) != 0) l.input.status = r.field();
  if ((has & 2u) != 0) l.input.fault_mask = r.u32();
  if ((has & 4u) != 0) l.input.velocity = r.field();
  l.output.report_id = r.u8();
  l.output.length = r.length();
  l.output.force = r.field();
  l.output.full_scale = r.number();
  if ((has & 8u) != 0) l.output.enable = hid::SwitchField{r.field(), r.number(), r.number()};
  if ((has & 16u) != 0) l.output.keepalive = r.field();
  l.enable_feature = r.feature((has & 32u) != 0);
  l.gain_feature = r.feature((has & 64u) != 0);
  l.watchdog_feature = r.feature((has & 128u) != 0);
  return l;
}

// --- bits: the model of HID's little-endian bit packing ---

bool bit_at(std::span<const std::uint8_t> d, std::uint64_t bit) {
  return bit / 8 < d.size() && ((d[bit / 8] >> (bit % 8)) & 1u) != 0;
}

// `before` with bits [offset, offset + bits) set to `value`'s, where they lie inside it.
Bytes put_model(Bytes d, std::uint64_t offset, std::uint32_t bits, std::uint32_t value) {
  for (std::uint32_t i = 0; i < bits; ++i) {
    const std::uint64_t b = offset + i;
    if (b / 8 >= d.size()) break;
    const auto mask = static_cast<std::uint8_t>(1u << (b % 8));
    d[b / 8] =
        static_cast<std::uint8_t>(((value >> i) & 1u) != 0 ? d[b / 8] | mask : d[b / 8] & ~mask);
  }
  return d;
}

void check_bits(Reader& r) {
  const std::uint8_t flags = r.u8();
  const std::uint32_t offset = (flags & 1u) != 0 ? r.u32() : r.u16();
  const std::uint32_t bits = r.u8() % 33u;
  const std::uint32_t value = r.u32();
  const std::span<const std::uint8_t> tail = r.rest();
  Bytes data(tail.begin(), tail.end());  // its own allocation: ASan sees any overrun
  std::uint32_t want = 0;
  for (std::uint32_t i = 0; i < bits; ++i)
    want |= static_cast<std::uint32_t>(bit_at(data, std::uint64_t{offset} + i)) << i;
  const std::uint32_t got = hid::get_bits(data, offset, bits);
  require(got == want, "get_bits reads the bits in HID order, 0 past the data");
  const Bytes expect = put_model(data, offset, bits, value);
  hid::put_bits(data, offset, bits, value);
  require(data == expect, "put_bits writes those bits only, and nothing past the data");
  const std::uint32_t mask = bits == 32 ? ~0u : (1u << bits) - 1u;
  if (std::uint64_t{offset} + bits <= 8 * std::uint64_t{data.size()}) {
    require(hid::get_bits(data, offset, bits) == (value & mask), "put_bits then get_bits");
  }
  const std::int64_t s = hid::field_value(got, bits, true);
  if (bits >= 1 && bits < 32) {
    const std::int64_t half = std::int64_t{1} << (bits - 1);
    require(s >= -half && s < half && (static_cast<std::uint32_t>(s) & mask) == got,
            "field_value sign-extends the field's own width");
  }
  require(hid::field_value(got, bits, false) == got, "field_value of an unsigned field");
}

// --- mode 0: descriptors and the PID layout ---

void check_error(const std::string& e, std::size_t size) {
  require(!e.empty(), "a refused descriptor says why");
  if (e.rfind("byte ", 0) == 0) {
    std::size_t at = 0;
    const auto [end, ec] = std::from_chars(e.data() + 5, e.data() + e.size(), at);
    require(ec == std::errc() && at < size && end[0] == ':', "the byte named is in the input", e);
    return;
  }
  // Errors about the descriptor as a whole name no byte (tests/hid/descriptor_test.cpp).
  const bool whole = size == 0 || size > hid::kMaxDescriptorSize ||
                     e.find("still open at the end of the descriptor") != std::string::npos ||
                     e.find("before any Report ID") != std::string::npos;
  require(whole, "an item's error names its byte", e);
}

void check_parsed(const hid::ParsedDescriptor& d) {
  require(d.fields.size() <= 1024, "at most 1024 fields");
  std::vector<std::uint64_t> used(d.reports.size(), 0);  // bits the fields so far fill
  for (const hid::ReportInfo& r : d.reports) {
    require(d.find_report(r.kind, r.id) == &r, "reports are unique by kind and id");
    require((r.id != 0) == d.numbered, "numbered descriptors number every report, others none");
    require(r.bits > 0 && r.data_bytes() <= 4096, "a report is 1 bit to 4096 bytes");
  }
  for (const hid::ReportField& f : d.fields) {
    const hid::ReportInfo* r = d.find_report(f.kind, f.report_id);
    require(r != nullptr, "find_report finds every field's report");
    require(f.bit_size >= 1 && f.bit_size <= 256 && f.count >= 1 && f.count <= 4096,
            "Report Size 1..256 and Count 1..4096");
    require(f.usages.size() <= 4096 && f.collections.size() <= 64, "usages and depth bounded");
    require(f.logical_min < 0 || f.logical_max >= 0, "a maximum is signed after a minimum < 0");
    const auto i = static_cast<std::size_t>(r - d.reports.data());
    require(f.bit_offset == used[i], "a report's fields follow one another");
    used[i] += std::uint64_t{f.bit_size} * f.count;
    require(used[i] <= r->bits, "every field lies inside its report's bits");
  }
  for (std::size_t i = 0; i < d.reports.size(); ++i)
    require(used[i] == d.reports[i].bits, "a report is its fields' bits");
}

// The values a slot's bits can hold, as get_slot reads them.
std::pair<std::int64_t, std::int64_t> representable(const hid::Slot& s) {
  const std::int64_t top = std::int64_t{1} << (s.bit_size - (s.is_signed ? 1 : 0));
  return {s.is_signed ? -top : 0, top - 1};
}

bool outside(const hid::Slot& s, std::int64_t v) { return v < s.logical_min || v > s.logical_max; }

// A report of `ref` with data from `fill`, one slot written and read back.
void check_slot(const hid::ReportRef& ref, bool numbered, const hid::Slot& s,
                std::span<const std::uint8_t> fill) {
  if (!s.present) return;
  require(ref.present && s.bit_size >= 1 && s.bit_size <= 32, "a slot is 1..32 bits of a report");
  require(std::uint64_t{s.bit_offset} + s.bit_size <= 8 * std::uint64_t{ref.data_bytes},
          "a slot lies inside its report");
  Bytes rep = hid::make_report(ref, numbered);
  const std::span<std::uint8_t> data = hid::data_of(std::span<std::uint8_t>(rep), ref, numbered);
  for (std::size_t i = 0; i < data.size() && !fill.empty(); ++i) data[i] = fill[i % fill.size()];
  const auto [lo, hi] = representable(s);
  const std::int64_t read = hid::get_slot(data, s);
  require(read >= lo && read <= hi, "get_slot reads a value of the slot's width");
  const std::int64_t mid = lo + static_cast<std::int64_t>(read - lo) / 2;
  for (const std::int64_t v : {s.logical_min, s.logical_max, mid, hid::null_value(s)}) {
    const Bytes before(data.begin(), data.end());
    hid::set_slot(data, s, v);
    const Bytes expect = put_model(before, s.bit_offset, s.bit_size, static_cast<std::uint32_t>(v));
    require(std::equal(data.begin(), data.end(), expect.begin(), expect.end()),
            "set_slot writes the slot's bits only");
    if (v >= lo && v <= hi) require(hid::get_slot(data, s) == v, "set_slot then get_slot");
  }
  // null_value() is the last value written. It must read outside the logical range whenever
  // some value of the slot's width does (an end of the width is then outside).
  if (outside(s, lo) || outside(s, hi)) {
    require(outside(s, hid::get_slot(data, s)), "null_value reads outside the logical range");
  }
}

// pid_status over `data`, bit by bit from pid_protocol.h's table.
void check_status(std::span<const std::uint8_t> data, const hid::PidLayout& l) {
  const std::pair<const hid::Slot&, std::uint32_t> table[] = {
      {l.st_paused, hid::kPidPaused},
      {l.st_actuators_enabled, hid::kPidActuatorsDisabled},
      {l.st_safety_switch, hid::kPidSafetySwitchOff},
      {l.st_override, hid::kPidOverride},
      {l.st_power, hid::kPidPowerOff},
      {l.st_playing, hid::kPidEffectStopped}};
  std::uint32_t want = 0;
  for (const auto& [slot, bit] : table) {
    const bool when_one = bit == hid::kPidPaused || bit == hid::kPidOverride;
    if (slot.present && (hid::get_slot(data, slot) != 0) == when_one) want |= bit;
  }
  require(hid::pid_status(data, l) == want, "pid_status sets the bits its fields say, no others");
}

// The reports the layout found: each of its kind, made, and recognised by id and length.
void check_pid_reports(const hid::ParsedDescriptor& d, const hid::PidLayout& l,
                       std::span<const std::uint8_t> fill) {
  using K = hid::ReportKind;
  const struct {
    const hid::ReportRef& ref;
    K kind;
    bool required;
  } reports[] = {{l.position_report, K::kInput, true}, {l.set_effect, K::kOutput, true},
                 {l.set_constant, K::kOutput, true},   {l.effect_operation, K::kOutput, true},
                 {l.device_control, K::kOutput, true}, {l.create_effect, K::kFeature, true},
                 {l.block_load, K::kFeature, true},    {l.device_gain, K::kOutput, false},
                 {l.block_free, K::kOutput, false},    {l.state, K::kInput, false}};
  for (const auto& [ref, kind, required] : reports) {
    require(ref.present || !required, "a found layout has every report the profile needs");
    if (!ref.present) continue;
    const hid::ReportInfo* info = d.find_report(ref.kind, ref.id);
    require(ref.kind == kind && info != nullptr && info->data_bytes() == ref.data_bytes,
            "a PID report is the descriptor's report of its kind");
    const Bytes rep = hid::make_report(ref, l.numbered);
    require(hid::is_report(rep, ref, l.numbered) &&
                hid::data_of(std::span<const std::uint8_t>(rep), ref, l.numbered).size() ==
                    ref.data_bytes,
            "make_report makes the report, data_of finds its data");
    // The fill cut to the report's size (or shorter), as a device might send it.
    const Bytes cut(fill.begin(),
                    fill.begin() + static_cast<std::ptrdiff_t>(std::min(fill.size(), rep.size())));
    const bool id_ok = (!l.numbered && kind == K::kInput) || (!cut.empty() && cut[0] == ref.id);
    require(hid::is_report(cut, ref, l.numbered) == (id_ok && cut.size() == rep.size()),
            "is_report: the id and the length");
    check_status(hid::data_of(std::span<const std::uint8_t>(cut), ref, l.numbered), l);
  }
}

// Every slot and choice the layout found, written and read back in its own report.
void check_pid_slots(const hid::PidLayout& l, std::span<const std::uint8_t> fill) {
  require(l.position.present && l.sc_magnitude.present && l.bl_block.present,
          "a found layout has the fields find_pid_layout needs");
  const std::pair<const hid::ReportRef&, std::vector<const hid::Slot*>> slots[] = {
      {l.position_report, {&l.position, &l.sequence}},
      {l.set_effect,
       {&l.se_block, &l.se_duration, &l.se_trigger_repeat, &l.se_sample_period, &l.se_start_delay,
        &l.se_gain, &l.se_trigger_button, &l.se_axis_x, &l.se_direction_enable, &l.se_direction}},
      {l.set_constant, {&l.sc_block, &l.sc_magnitude}},
      {l.effect_operation, {&l.eo_block, &l.eo_loop_count}},
      {l.block_load, {&l.bl_block, &l.bl_ram_pool}},
      {l.device_gain, {&l.dg_gain}},
      {l.block_free, {&l.bf_block}},
      {l.state,
       {&l.st_paused, &l.st_actuators_enabled, &l.st_safety_switch, &l.st_override, &l.st_power,
        &l.st_playing}}};
  for (const auto& [ref, list] : slots) {
    for (const hid::Slot* s : list) check_slot(ref, l.numbered, *s, fill);
  }
  const std::pair<const hid::ReportRef&, std::vector<const hid::Choice*>> choices[] = {
      {l.set_effect, {&l.se_constant}},
      {l.effect_operation, {&l.eo_start, &l.eo_stop}},
      {l.device_control, {&l.dc_enable, &l.dc_disable, &l.dc_stop_all, &l.dc_reset}},
      {l.create_effect, {&l.ce_constant}},
      {l.block_load, {&l.bl_success, &l.bl_full, &l.bl_error}}};
  for (const auto& [ref, list] : choices) {
    for (const hid::Choice* c : list) {
      check_slot(ref, l.numbered, c->slot, fill);
      if (!c->slot.present) continue;
      Bytes rep = hid::make_report(ref, l.numbered);
      const std::span<std::uint8_t> data =
          hid::data_of(std::span<std::uint8_t>(rep), ref, l.numbered);
      hid::choose(data, *c);
      const auto [lo, hi] = representable(c->slot);
      if (c->value >= lo && c->value <= hi) require(hid::chosen(data, *c), "choose then chosen");
    }
  }
}

void check_descriptor(std::span<const std::uint8_t> bytes, bool with_sequence) {
  const hid::DescriptorParse p = hid::parse_report_descriptor(bytes);
  if (!p.descriptor) return check_error(p.error, bytes.size());
  require(p.error.empty(), "a parsed descriptor has no error");
  check_parsed(*p.descriptor);
  const hid::PidFind f = hid::find_pid_layout(*p.descriptor, hid::kGenericDesktopX,
                                              with_sequence ? hid::kReferenceSequenceUsage : 0);
  require(f.layout.has_value() == f.error.empty(), "a PID layout, or an error naming the gap");
  if (!f.layout) return;
  check_pid_reports(*p.descriptor, *f.layout, bytes);
  check_pid_slots(*f.layout, bytes);
}

// --- mode 1: a `report` profile layout ---

// Counts of slack in a round trip through `f`: rounding to an integer, or to a float.
double quantum(const hid::FieldSpec& f, double raw) {
  if (hid::is_integer(f.type)) return 0.5;
  return std::max(std::abs(raw) * 0x1p-24, 0x1p-149) * 2.0;
}

// |got - want| within `counts` of `f`, plus the rounding of the affine map itself.
bool near(double got, double want, double counts, const hid::FieldSpec& f, double raw) {
  const double eps = std::numeric_limits<double>::epsilon();
  const double slack = 8 * eps * (std::abs(raw * f.scale) + std::abs(f.offset) + std::abs(want));
  return std::abs(got - want) <=
         counts * std::abs(f.scale) + slack + 8 * std::numeric_limits<double>::denorm_min();
}

// SI value of raw count `k` of `f`, when k is one of the type's values and nothing overflows.
std::optional<double> si_of(const hid::FieldSpec& f, double k) {
  if (!(k >= hid::raw_min(f.type) && k <= hid::raw_max(f.type))) return std::nullopt;
  const double si = k * f.scale + f.offset;
  if (!std::isfinite(k * f.scale) || !std::isfinite(si) || !std::isfinite(si - f.offset)) {
    return std::nullopt;
  }
  return si;
}

void check_input_round_trip(const hid::InputLayout& in, Reader& r) {
  const double k_pos = r.number(), k_vel = r.number(), any = r.number();
  hid::InputValues v;
  v.position = si_of(in.position, k_pos).value_or(any);  // else any value, NaN too
  v.velocity = in.velocity ? si_of(*in.velocity, k_vel).value_or(0.0) : 0.0;
  v.sequence = r.u32();
  v.status = r.u32();
  Bytes rep(hid::input_report_size(in));
  hid::encode_input(v, in, rep);
  hid::InputValues got;
  require(hid::decode_input(rep, in, got) == hid::InputDecode::kOk, "an encoded input decodes");
  if (si_of(in.position, k_pos)) {
    require(near(got.position, v.position, quantum(in.position, k_pos), in.position, k_pos),
            "the position comes back within the field's quantisation");
  } else if (std::isnan(v.position)) {
    require(got.position == in.position.offset, "a NaN position is sent as raw 0");
  }
  if (in.velocity && si_of(*in.velocity, k_vel)) {
    require(near(got.velocity, v.velocity, quantum(*in.velocity, k_vel), *in.velocity, k_vel),
            "the velocity comes back within the field's quantisation");
  }
  if (in.sequence) {
    require(got.sequence == v.sequence % hid::counter_modulus(in.sequence->type),
            "the sequence comes back modulo its counter");
  }
  if (in.status) {
    const double top = hid::raw_max(in.status->type);
    require(got.status == std::min<double>(v.status, top), "the status comes back, clamped");
  }
}

// As the driver sends it: id, the enable switch, then the force (report_profile.cpp).
void check_output_round_trip(const hid::OutputLayout& o, double force) {
  for (const bool on : {true, false}) {
    Bytes rep(hid::wire_size(o.length), 0);
    rep[0] = o.report_id;
    if (o.enable) {
      const hid::FieldSpec& e = o.enable->field;
      hid::write_raw(rep.data() + 1 + e.byte, e.type, e.endian, on ? o.enable->on : o.enable->off);
    }
    hid::encode_force(force, o, rep);
    const hid::FieldSpec& f = o.force;
    const double raw = hid::read_raw(rep.data() + 1 + f.byte, f.type, f.endian);
    require(std::abs(raw) <= o.full_scale, "the force written is within +-full_scale counts");
    hid::OutputValues got;
    require(hid::decode_output(rep, o, got), "an encoded output report decodes");
    require(got.enable == (on || !o.enable), "the enable field reads back as written");
    const double r = (force - f.offset) / f.scale;
    if (std::isnan(r)) continue;
    const double want = std::clamp(r, std::max(-o.full_scale, hid::raw_min(f.type)), o.full_scale);
    require(std::abs(raw - want) <= quantum(f, want), "the force written is the clamped force");
    require(near(got.force, want * f.scale + f.offset, 1.0, f, want),
            "decode_output gives back the clamped force within one count");
  }
}

void check_feature_round_trip(const std::optional<hid::FeatureLayout>& f, bool is_switch) {
  if (!f) return;
  Bytes rep(hid::wire_size(f->length));
  hid::encode_feature(f->on, *f, rep);
  std::optional<double> got = hid::decode_feature(rep, *f);
  require(got && *got == f->on, "a feature's value reads back as written");
  if (!is_switch) return;
  hid::encode_feature(f->off, *f, rep);
  got = hid::decode_feature(rep, *f);
  require(got && *got == f->off && *got != f->on, "a feature switched off does not read on");
}

// One report as a device (or, for output and feature reports, the host) might send it.
void check_decode(const Bytes& rep, const hid::ReportProfileLayout& l) {
  const hid::InputLayout& in = l.input;
  const bool numbered = in.report_id != 0;
  hid::InputValues v;
  const hid::InputDecode d = hid::decode_input(rep, in, v);
  const hid::InputDecode want =
      rep.empty()                                   ? hid::InputDecode::kEmpty
      : numbered && rep[0] != in.report_id          ? hid::InputDecode::kOtherReport
      : rep.size() - (numbered ? 1 : 0) < in.length ? hid::InputDecode::kTooShort
                                                    : hid::InputDecode::kOk;
  require(d == want, "decode_input: empty, another id, too short, or ok");
  const hid::OutputLayout& o = l.output;
  hid::OutputValues out;
  const bool ours = rep.size() >= hid::wire_size(o.length) && rep[0] == o.report_id;
  require(hid::decode_output(rep, o, out) == ours, "decode_output: its id and length");
  if (ours &&
      !std::isnan(hid::read_raw(rep.data() + 1 + o.force.byte, o.force.type, o.force.endian))) {
    require(near(out.force, o.force.offset, o.full_scale, o.force, o.full_scale),
            "a decoded force lies within +-full_scale counts");
  }
  for (const auto* f : {&l.enable_feature, &l.gain_feature, &l.watchdog_feature}) {
    if (!*f) continue;
    const bool mine = rep.size() >= hid::wire_size((*f)->length) && rep[0] == (*f)->report_id;
    require(hid::decode_feature(rep, **f).has_value() == mine, "decode_feature: id and length");
  }
}

void check_layout(Reader& r) {
  const hid::ReportProfileLayout l = layout(r);
  const double max_force = r.number();
  const std::vector<std::string> problems = hid::validate(l, max_force);
  for (const std::string& p : problems) {
    require(p.find(": ") != std::string::npos && p.find(": ") > 0, "a problem names where", p);
  }
  if (!problems.empty()) return;
  check_input_round_trip(l.input, r);
  check_output_round_trip(l.output, r.number());
  check_feature_round_trip(l.enable_feature, true);
  check_feature_round_trip(l.gain_feature, false);
  check_feature_round_trip(l.watchdog_feature, false);
  const std::span<const std::uint8_t> tail = r.rest();  // a report of any kind or length
  check_decode(Bytes(tail.begin(), tail.end()), l);     // its own allocation: ASan sees overreads
}

// --- mode 2: the loopback framing ---

void check_frame(std::span<const std::uint8_t> m) {
  static constexpr std::uint8_t kTypes[] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x83, 0x84, 0x85};
  const std::optional<hid::FrameView> v = hid::parse_frame(m);
  const bool known =
      !m.empty() && std::find(std::begin(kTypes), std::end(kTypes), m[0]) != std::end(kTypes);
  require(v.has_value() == known, "parse_frame takes exactly the eight message types");
  if (!v) return;
  require(v->payload.data() == m.data() + 1 && v->payload.size() == m.size() - 1,
          "the payload is the rest of the message");
  const Bytes same(m.begin(), m.end());
  require(hid::frame(v->type, v->payload) == same, "frame() rebuilds the message");
  Bytes out(m.size());
  require(hid::write_frame(v->type, v->payload, out) == m.size() && out == same,
          "write_frame rebuilds the message in a buffer of its size");
  const bool is_reply = (m[0] & 0x80u) != 0;
  if (is_reply && !v->payload.empty()) {
    require(hid::reply(v->type, v->payload[0], v->payload.subspan(1)) == same,
            "reply() rebuilds a reply from its status and payload");
  }
  if (v->type == hid::FrameType::kGetFeature && v->payload.size() == 3) {
    const auto max = static_cast<std::uint16_t>(v->payload[1] | v->payload[2] << 8);
    require(hid::get_feature_request(v->payload[0], max) == same, "get_feature_request");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Reader r({data + 1, size - 1});
  const unsigned mode = data[0] & 3u;
  if (mode == 0) check_descriptor(r.rest(), (data[0] & 4u) != 0);
  if (mode == 1) check_layout(r);
  if (mode == 2) check_frame(r.rest());
  if (mode == 3) check_bits(r);
  return 0;
}
