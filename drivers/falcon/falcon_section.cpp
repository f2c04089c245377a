#include <cmath>
#include <stdexcept>
#include <string>

#include "drivers/falcon/falcon_settings.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::falcon {
namespace {

using config::schema::Diagnostics;
using config::schema::Field;
using config::schema::format_number;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;

void read_firmware(MapReader& m, FalconSettings& s) {
  const Field f = m.take("firmware");
  if (!f.present || f.node.IsNull()) {
    m.missing("firmware",
              "the absolute path of Novint's firmware image (docs/drivers/falcon.md: hapticd "
              "does not ship it)");
    return;
  }
  if (const auto v = config::schema::read_string(m.diag(), f)) {
    if (v->empty() || (*v)[0] != '/') {
      m.diag().error(f.key_mark, f.path, "must be an absolute path, got '" + *v + "'");
    }
    s.firmware = *v;
  }
}

// The Falcon is a delta of three arms: its joints are the arms' angles.
void check_kinematics(MapReader& m, const config::Config& cfg) {
  if (cfg.device.kinematics.kind == kinematics::Kind::kDelta) return;
  m.diag().error(m.mark(), m.path(),
                 "the Falcon's three arms drive a delta, but device.kinematics is " +
                     std::string(kinematics::kind_name(cfg.device.kinematics.kind)) +
                     ": set device.kinematics: {kind: delta}");
}

// A motor command is a signed 16-bit count: a torque limit beyond what it carries would be cut
// short on the wire, which hapticd never does silently.
void check_reach(MapReader& m, const FalconSettings& s, const config::Config& cfg) {
  const double reach = 32767.0 / std::abs(s.counts_per_newton_metre);
  for (std::size_t j = 0; j < 3; ++j) {
    if (cfg.device.max_force[j] <= reach) continue;
    m.diag().error(m.mark(), m.path() + ".counts_per_newton_metre",
                   format_number(s.counts_per_newton_metre) + " counts per N m carry at most " +
                       format_number(reach) + " N m in a motor command (32767 counts), below " +
                       "device.max_force " + format_number(cfg.device.max_force[j]) + " of joint " +
                       std::to_string(j));
    return;
  }
}

}  // namespace

std::shared_ptr<const config::DriverSettings> read_falcon_section(MapReader& m,
                                                                  const config::Config& cfg) {
  Diagnostics& d = m.diag();
  const std::size_t errors_before = d.messages().size();
  auto s = std::make_shared<FalconSettings>();
  read_firmware(m, *s);
  if (const auto v = config::schema::read_string(d, m.take("serial"))) s->serial = *v;
  integer(m, "load_tries", IntRange::between(1, 20), s->load_tries);
  const Field counts = m.take("counts_per_newton_metre");
  number(m, counts, Range::interval(-1e6, true, 1e6, true), s->counts_per_newton_metre);
  if (counts.present && s->counts_per_newton_metre == 0.0) {
    d.error(counts.key_mark, counts.path, "must not be 0 (its sign is the force's direction)");
  }
  number(m, "homing_timeout_s", Range::interval(1.0, true, 3600.0, true), s->homing_timeout_s);
  number(m, "liveness_ms", Range::interval(5.0, true, 10'000.0, true), s->liveness_ms);
  check_kinematics(m, cfg);
  if (s->counts_per_newton_metre != 0.0) check_reach(m, *s, cfg);
  if (d.messages().size() != errors_before) return nullptr;
  return s;
}

const FalconSettings& falcon_settings(const DriverContext& ctx) {
  const auto* s = dynamic_cast<const FalconSettings*>(ctx.settings.get());
  if (s == nullptr) {
    throw std::logic_error("device.driver is not falcon: no device.falcon settings");
  }
  return *s;
}

int declared_delay_samples(double sample_period_s) noexcept {
  return round_trip_delay_samples(1.0, sample_period_s);
}

}  // namespace hapticd::drivers::falcon
