#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "drivers/field/field_schema.h"
#include "drivers/serial/serial_settings.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::serial {
namespace {

using config::schema::Diagnostics;
using config::schema::Field;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;

std::string at(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

// A list of bytes, each decimal or 0x hexadecimal: [0xA5, 0x5A]. Nothing after a problem.
std::vector<std::uint8_t> byte_list(Diagnostics& d, const Field& f, std::size_t max) {
  std::vector<std::uint8_t> out;
  if (!f.present || f.node.IsNull()) return out;
  if (!f.node.IsSequence() || f.node.size() > max) {
    d.error(f.key_mark, f.path,
            "must be a list of at most " + std::to_string(max) + " bytes ([0xA5, 0x5A]), got " +
                (f.node.IsSequence() ? std::to_string(f.node.size()) + " entries"
                                     : config::schema::describe_value(f.node)));
    return out;
  }
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    const auto v =
        config::schema::read_hex(d, Field{at(f.path, i), f.node[i], f.key_mark, true}, 255);
    if (!v) return {};
    out.push_back(static_cast<std::uint8_t>(*v));
  }
  return out;
}

// A list of fields, one per joint (positions, forces).
std::vector<FieldSpec> field_list(MapReader& m, const char* key, const char* why,
                                  std::size_t max_byte) {
  std::vector<FieldSpec> out;
  const Field f = m.take(key);
  if (!f.present) m.missing(key, why);
  if (!f.present) return out;
  if (!f.node.IsSequence() || f.node.size() == 0 || f.node.size() > base::kMaxJoints) {
    m.diag().error(f.key_mark, f.path,
                   "must be a list of 1 to " + std::to_string(base::kMaxJoints) +
                       " fields, joint i being entry i, got " +
                       config::schema::describe_value(f.node));
    return out;
  }
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    MapReader e(m.diag(), Field{at(f.path, i), f.node[i], f.node[i].Mark(), true});
    out.push_back(field::read_spec(e, max_byte, true));
    e.finish();
  }
  return out;
}

std::optional<FieldSpec> optional_field(MapReader& m, const char* key, std::size_t max_byte) {
  const Field f = m.take(key);
  if (!f.present || f.node.IsNull()) return std::nullopt;
  MapReader e(m.diag(), f);
  FieldSpec spec = field::read_spec(e, max_byte, false);
  e.finish();
  return spec;
}

// sync and length, and the check: {algorithm, byte, from, to, endian}.
FrameShape read_shape(MapReader& m) {
  FrameShape s;
  s.sync = byte_list(m.diag(), m.take("sync"), kMaxSync);
  const Field length = m.take("length");
  if (!length.present) m.missing("length", "the whole frame's bytes, sync and check included");
  integer(m, length, IntRange::between(1, kMaxFrame), s.length);
  const Field check = m.take("check");
  if (!check.present || check.node.IsNull()) return s;
  MapReader c(m.diag(), check);
  FrameCheck fc;
  std::vector<std::string> names;
  for (const CheckAlgorithm& a : check_algorithms()) names.emplace_back(a.name);
  const Field algorithm = c.take("algorithm");
  if (!algorithm.present) c.missing("algorithm", "sum8, xor8, crc-8/smbus, crc-16/ibm-3740...");
  const auto choice = config::schema::read_choice(m.diag(), algorithm, names);
  fc.algorithm = choice ? &check_algorithms()[*choice] : nullptr;
  const Field byte = c.take("byte");
  if (!byte.present) c.missing("byte", "where the check sits in the frame");
  integer(c, byte, IntRange::between(0, kMaxFrame - 1), fc.at);
  fc.from = s.sync.size();
  fc.to = fc.at;  // by default: every byte after the sync, up to the check
  integer(c, "from", IntRange::between(0, kMaxFrame - 1), fc.from);
  integer(c, "to", IntRange::between(1, kMaxFrame), fc.to);
  if (const auto e = config::schema::read_choice(m.diag(), c.take("endian"), {"little", "big"})) {
    fc.endian = *e == 0 ? field::Endian::kLittle : field::Endian::kBig;
  }
  c.finish();
  if (fc.algorithm != nullptr) s.check = fc;
  return s;
}

// A layout's problems, at the line of its frame's key (input:, output:).
void report(MapReader& m, const Field& frame, const std::vector<std::string>& errors) {
  for (const std::string& e : errors) {
    const auto colon = e.find(": ");
    m.diag().error(frame.key_mark, m.path() + "." + e.substr(0, colon), e.substr(colon + 2));
  }
}

void read_input(MapReader& parent, SerialSettings& s) {
  const Field f = parent.take("input");
  if (!f.present) parent.missing("input", "the frame the device sends: sync, length, positions");
  MapReader m(parent.diag(), f);
  s.input.shape = read_shape(m);
  s.input.positions = field_list(
      m, "positions", "one field per joint: [{byte: 1, type: f32, scale: 1}]", kMaxFrame - 1);
  s.input.sequence = optional_field(m, "sequence", kMaxFrame - 1);
  s.input.status = optional_field(m, "status", kMaxFrame - 1);
  if (const auto v = config::schema::read_hex(m.diag(), m.take("fault_mask"), 0xFFFFFFFFu)) {
    s.input.fault_mask = *v;
  }
  m.finish();
  if (f.present && m.ok()) report(parent, f, validate(s.input, "input"));
}

void read_output(MapReader& parent, SerialSettings& s) {
  const Field f = parent.take("output");
  if (!f.present) parent.missing("output", "the frame hapticd sends: sync, length, forces");
  MapReader m(parent.diag(), f);
  s.output.shape = read_shape(m);
  s.output.forces = field_list(m, "forces", "one field per joint: [{byte: 2, type: f32, scale: 1}]",
                               kMaxFrame - 1);
  const Field enable = m.take("enable");
  if (enable.present && !enable.node.IsNull()) {
    MapReader e(m.diag(), enable);
    EnableField en;
    en.field = field::read_spec(e, kMaxFrame - 1, false);
    number(e, e.take("on"), Range::any(), en.on);
    number(e, e.take("off"), Range::any(), en.off);
    e.finish();
    s.output.enable = en;
  }
  m.finish();
  if (f.present && m.ok()) report(parent, f, validate(s.output, "output"));
}

void read_startup(MapReader& m, SerialSettings& s) {
  const Field f = m.take("startup");
  if (!f.present || f.node.IsNull()) return;
  if (!f.node.IsSequence()) {
    m.diag().error(f.key_mark, f.path, "must be a list of frames, each a list of bytes");
    return;
  }
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    s.startup.push_back(
        byte_list(m.diag(), Field{at(f.path, i), f.node[i], f.key_mark, true}, kMaxFrame));
  }
}

// Each joint a position and a force; each force field able to carry device.max_force.
void check_joints(MapReader& m, const SerialSettings& s, const config::Config& cfg) {
  const auto joints = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  for (const auto& [n, key] : {std::pair{s.input.positions.size(), "input.positions"},
                               {s.output.forces.size(), "output.forces"}}) {
    if (n == 0 || n == joints) continue;
    m.diag().error(m.mark(), m.path() + "." + key,
                   std::to_string(n) + " field(s) for a mechanism of " + std::to_string(joints) +
                       " joint(s) (device.kinematics): one per joint, joint i is entry i");
  }
  for (std::size_t i = 0; i < s.output.forces.size() && i < joints; ++i) {
    const FieldSpec& f = s.output.forces[i];
    const double reach =
        std::min(std::abs(field::raw_max(f)), std::abs(field::raw_min(f))) * std::abs(f.scale);
    const double need = cfg.device.max_force[i];
    if (f.scale == 0.0 || (f.is_signed || f.is_float ? reach : 0.0) < need) {
      m.diag().error(
          m.mark(), at(m.path() + ".output.forces", i),
          "carries at most " + config::schema::format_number(reach) +
              " either way (a signed field of scale N per count), below device.max_force " +
              config::schema::format_number(need));
    }
  }
}

}  // namespace

std::shared_ptr<const config::DriverSettings> read_serial_section(MapReader& m,
                                                                  const config::Config& cfg) {
  Diagnostics& d = m.diag();
  const std::size_t errors_before = d.messages().size();
  auto s = std::make_shared<SerialSettings>();
  const Field port = m.take("port");
  if (!port.present || port.node.IsNull()) {
    m.missing("port", "the serial port: /dev/ttyACM0 or /dev/serial/by-id/...");
  } else if (const auto v = config::schema::read_string(d, port)) {
    if (v->empty() || (*v)[0] != '/') {
      d.error(port.key_mark, port.path,
              "must be the port's path (/dev/ttyACM0, /dev/serial/by-id/...)");
    }
    s->port = *v;
  }
  const Field baud = m.take("baud");
  if (const auto v = config::schema::read_integer(d, baud, IntRange::between(1, 4'000'000))) {
    if (std::find(std::begin(kBaudRates), std::end(kBaudRates), *v) == std::end(kBaudRates)) {
      d.error(baud.key_mark, baud.path,
              std::to_string(*v) +
                  " is no rate a Linux port takes (9600, 19200, 38400, 57600, "
                  "115200, 230400, 460800, 500000, 921600, 1000000 ... 4000000)");
    } else {
      s->baud = static_cast<std::uint32_t>(*v);
    }
  }
  if (const auto v = config::schema::read_choice(d, m.take("exchange"), {"request", "stream"})) {
    s->exchange = *v == 0 ? Exchange::kRequest : Exchange::kStream;
  }
  number(m, "latency_ms", Range::interval(0.0, false, 100.0, true), s->latency_ms);
  number(m, "liveness_ms", Range::interval(1.0, true, 60'000.0, true), s->liveness_ms);
  number(m, "answer_timeout_ms", Range::interval(1.0, true, 60'000.0, true), s->answer_timeout_ms);
  integer(m, "out_full_fault", IntRange::between(1, 1000), s->out_full_fault);
  read_startup(m, *s);
  number(m, "startup_gap_ms", Range::interval(0.0, true, 10'000.0, true), s->startup_gap_ms);
  read_input(m, *s);
  read_output(m, *s);
  if (d.messages().size() == errors_before) check_joints(m, *s, cfg);
  if (s->liveness_ms < 2.0 * s->latency_ms) {
    d.error(m.mark(), m.path() + ".liveness_ms",
            "must be at least twice latency_ms (a frame's way there and back)");
  }
  if (d.messages().size() != errors_before) return nullptr;
  return s;
}

const SerialSettings& serial_settings(const DriverContext& ctx) {
  const auto* s = dynamic_cast<const SerialSettings*>(ctx.settings.get());
  if (s == nullptr)
    throw std::logic_error("device.driver is not serial: no device.serial settings");
  return *s;
}

int declared_delay_samples(const SerialSettings& s, double sample_period_s) noexcept {
  return round_trip_delay_samples(s.latency_ms, sample_period_s);
}

}  // namespace hapticd::drivers::serial
