#include "support/hid_layout_oracle.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/field/field.h"
#include "drivers/hid/report_layout.h"
#include "drivers/io/counter_unwrap.h"
#include "support/check.h"

namespace hapticd::fuzz {
namespace {

namespace hid = hapticd::drivers::hid;
using Bytes = std::vector<std::uint8_t>;

// Its first byte says which optional parts follow, read in the order of report_layout.h's
// structs (support/hid_layout_oracle.h).
hid::ReportProfileLayout read_layout(HidInput& r) {
  const std::uint8_t has = r.u8();
  hid::ReportProfileLayout l;
  l.input.report_id = r.u8();
  l.input.length = r.length();
  l.input.position = r.field();
  l.input.position_wraps = r.last_wraps();
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

// Counts of slack in a round trip through `f`: rounding to an integer, or to a float.
double quantum(const hid::FieldSpec& f, double raw) {
  if (hid::is_integer(f)) return 0.5;
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
  if (!(k >= hid::raw_min(f) && k <= hid::raw_max(f))) return std::nullopt;
  const double si = k * f.scale + f.offset;
  if (!std::isfinite(k * f.scale) || !std::isfinite(si) || !std::isfinite(si - f.offset)) {
    return std::nullopt;
  }
  return si;
}

// The field's raw count by its definition (drivers/field/field.h), bit by bit: its bytes
// as one integer in its byte order, bits bit..bit+bits-1 of it, sign-extended when signed.
std::int64_t model_count(std::span<const std::uint8_t> data, const hid::FieldSpec& f) {
  const std::size_t n = f.span();
  std::uint64_t v = 0;
  for (unsigned i = 0; i < f.bits; ++i) {
    const unsigned p = f.bit + i;
    const std::size_t k =
        f.endian == hid::Endian::kLittle ? f.byte + p / 8 : f.byte + n - 1 - p / 8;
    v |= std::uint64_t{(data[k] >> (p % 8)) & 1u} << i;
  }
  if (f.is_signed && (v >> (f.bits - 1)) != 0) v |= ~std::uint64_t{0} << f.bits;
  return static_cast<std::int64_t>(v);
}

// Writing a field touches its own bits and no other: the bytes it shares stay as they were.
void check_field_isolation(const Bytes& data, const hid::FieldSpec& f, double raw) {
  if (f.end() > data.size()) return;
  Bytes after = data;
  hid::write_raw(after.data(), f, raw);
  for (std::size_t k = 0; k < data.size(); ++k) {
    require(((after[k] ^ data[k]) & ~f.mask_of_byte(k) & 0xFF) == 0,
            "writing a field leaves the other bits of its bytes alone");
  }
  if (hid::is_integer(f)) {
    require(hid::read_count(after.data(), f) == model_count(after, f),
            "read_count reads the field as its definition says");
  }
}

// A wrapping position: written modulo its width, and followed across the wrap by
// drivers/io/counter_unwrap.h as the driver follows it, step by step (each under half a range).
void check_wrapping(const hid::InputLayout& in, HidInput& r) {
  const hid::FieldSpec& f = in.position;
  if (!in.position_wraps || !hid::is_integer(f) || f.bits < 2) return;
  Bytes data(f.end(), 0);
  std::int64_t real = static_cast<std::int32_t>(r.u32());
  io::CounterUnwrap unwrap(static_cast<int>(f.bits), f.is_signed);
  const std::int64_t half = std::int64_t{1} << (f.bits - 1);
  for (int i = 0; i < 8; ++i) {
    hid::write_wrapped(data.data(), f, real);
    const std::int64_t raw = hid::read_count(data.data(), f);
    require(((raw - real) & ((half << 1) - 1)) == 0, "a wrapped count is the count mod 2^bits");
    if (i == 0) real = raw;  // the first reading is taken as it is: it decides the turn
    require(unwrap.next(static_cast<std::uint64_t>(raw)) == real,
            "the unwrapped count follows the real one");
    real += static_cast<std::int32_t>(r.u32()) % half;
  }
}

void check_input_round_trip(const hid::InputLayout& in, HidInput& r) {
  const double k_pos = r.number(), k_vel = r.number(), any = r.number();
  hid::InputValues v;
  v.position[0] = si_of(in.position, k_pos).value_or(any);  // else any value, NaN too
  v.velocity = in.velocity ? si_of(*in.velocity, k_vel).value_or(0.0) : 0.0;
  v.sequence = r.u32();
  v.status = r.u32();
  Bytes rep(hid::input_report_size(in));
  hid::encode_input(v, in, rep);
  hid::InputValues got;
  require(hid::decode_input(rep, in, got) == hid::InputDecode::kOk, "an encoded input decodes");
  if (si_of(in.position, k_pos)) {
    require(near(got.position[0], v.position[0], quantum(in.position, k_pos), in.position, k_pos),
            "the position comes back within the field's quantisation");
  } else if (std::isnan(v.position[0])) {
    require(got.position[0] == in.position.offset, "a NaN position is sent as raw 0");
  }
  if (in.velocity && si_of(*in.velocity, k_vel)) {
    require(near(got.velocity, v.velocity, quantum(*in.velocity, k_vel), *in.velocity, k_vel),
            "the velocity comes back within the field's quantisation");
  }
  if (in.sequence) {
    require(got.sequence == v.sequence % hid::counter_modulus(*in.sequence),
            "the sequence comes back modulo its counter");
  }
  if (in.status) {
    const double top = hid::raw_max(*in.status);
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
      hid::write_raw(rep.data() + 1, e, on ? o.enable->on : o.enable->off);
    }
    hid::encode_force(std::span<const double>(&force, 1), o, rep);
    const hid::FieldSpec& f = o.force;
    const double raw = hid::read_raw(rep.data() + 1, f);
    require(std::abs(raw) <= o.full_scale, "the force written is within +-full_scale counts");
    hid::OutputValues got;
    require(hid::decode_output(rep, o, got), "an encoded output report decodes");
    require(got.enable == (on || !o.enable), "the enable field reads back as written");
    const double r = (force - f.offset) / f.scale;
    if (std::isnan(r)) continue;
    const double want = std::clamp(r, std::max(-o.full_scale, hid::raw_min(f)), o.full_scale);
    require(std::abs(raw - want) <= quantum(f, want), "the force written is the clamped force");
    require(near(got.force[0], want * f.scale + f.offset, 1.0, f, want),
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
  if (d == hid::InputDecode::kOk && hid::is_integer(in.position)) {
    const std::span<const std::uint8_t> data = std::span(rep).subspan(numbered ? 1 : 0);
    require(v.position_count[0] == model_count(data, in.position),
            "the position's count is its bits as the field's definition reads them");
    if (in.sequence) {
      require(v.sequence == static_cast<std::uint32_t>(model_count(data, *in.sequence)),
              "the sequence is its bits");
    }
  }
  const hid::OutputLayout& o = l.output;
  hid::OutputValues out;
  const bool ours = rep.size() >= hid::wire_size(o.length) && rep[0] == o.report_id;
  require(hid::decode_output(rep, o, out) == ours, "decode_output: its id and length");
  if (ours && !std::isnan(hid::read_raw(rep.data() + 1, o.force))) {
    require(near(out.force[0], o.force.offset, o.full_scale, o.force, o.full_scale),
            "a decoded force lies within +-full_scale counts");
  }
  for (const auto* f : {&l.enable_feature, &l.gain_feature, &l.watchdog_feature}) {
    if (!*f) continue;
    const bool mine = rep.size() >= hid::wire_size((*f)->length) && rep[0] == (*f)->report_id;
    require(hid::decode_feature(rep, **f).has_value() == mine, "decode_feature: id and length");
  }
}

}  // namespace

void check_hid_layout(HidInput& r) {
  const hid::ReportProfileLayout l = read_layout(r);
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
  check_wrapping(l.input, r);
  const std::span<const std::uint8_t> tail = r.rest();  // a report of any kind or length
  const Bytes report(tail.begin(), tail.end());         // its own allocation: ASan sees overreads
  check_decode(report, l);
  check_field_isolation(report, l.input.position, r.number());
}

}  // namespace hapticd::fuzz
