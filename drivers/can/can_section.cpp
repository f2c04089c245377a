#include "drivers/can/can_settings.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <vector>

#include "drivers/device.h"

namespace hapticd::drivers::can {
namespace {

using config::schema::Field;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;

void required_number(MapReader& m, std::string_view key, const Range& range, double& out,
                     const std::string& why) {
  const Field f = m.take(key);
  if (!f.present) {
    m.missing(key, why);
    return;
  }
  if (const auto v = read_number(m.diag(), f, range)) out = *v;
}

void read_cia402(MapReader& can, bool selected, CanSettings& s) {
  if (!selected) {
    can.not_used("cia402", "profile odrive");
    return;
  }
  MapReader m(can.diag(), can.take("cia402"));
  if (!m.ok()) return;
  Cia402Settings& c = s.cia402;
  if (const auto v = read_choice(m.diag(), m.take("pdo_mapping"), {"configure", "verify"})) {
    c.pdo_mapping = *v == 0 ? PdoMapping::kConfigure : PdoMapping::kVerify;
  }
  if (const auto v = read_bool(m.diag(), m.take("map_velocity"))) c.map_velocity = *v;
  integer(m, "heartbeat_producer_ms", IntRange::between(1, 65535), c.heartbeat_producer_ms);
  integer(m, "master_node_id", IntRange::between(1, 127), c.master_node_id);
  integer(m, "master_heartbeat_ms", IntRange::between(0, 65535), c.master_heartbeat_ms);
  const Field watchdog = m.take("drive_watchdog_ms");
  if (const auto v = read_integer(m.diag(), watchdog, IntRange::between(0, 65535))) {
    c.drive_watchdog_ms = static_cast<int>(*v);
    if (c.drive_watchdog_ms != 0 && c.drive_watchdog_ms <= c.master_heartbeat_ms) {
      m.diag().error(watchdog.key_mark, watchdog.path,
                     "must be longer than master_heartbeat_ms (" +
                         std::to_string(c.master_heartbeat_ms) +
                         "), or the drive times out between two heartbeats");
    }
    if (c.drive_watchdog_ms != 0 && c.master_heartbeat_ms == 0) {
      m.diag().error(watchdog.key_mark, watchdog.path,
                     "needs master_heartbeat_ms > 0: the drive would watch a heartbeat nobody "
                     "sends");
    }
  }
  if (const auto v = read_choice(m.diag(), m.take("comm_loss_reaction"),
                                 {"none", "fault", "disable_voltage", "quick_stop"})) {
    c.comm_loss_reaction = static_cast<cia402::CommLossReaction>(*v);
  }
  integer(m, "dc_link_timeout_ms", IntRange::between(0, 600'000), c.dc_link_timeout_ms);
  m.finish();
}

void read_odrive(MapReader& can, bool selected, CanSettings& s) {
  if (!selected) {
    can.not_used("odrive", "profile cia402");
    return;
  }
  MapReader m(can.diag(), can.take("odrive"));
  if (!m.ok()) return;
  OdriveSettings& o = s.odrive;
  if (const auto v = read_choice(m.diag(), m.take("firmware"), {"auto", "0.5", "0.6"})) {
    o.detect_firmware = *v == 0;
    o.firmware = *v == 1 ? odrive::Firmware::k05 : odrive::Firmware::k06;
  }
  if (const auto v = read_choice(m.diag(), m.take("position_source"), {"request", "cyclic"})) {
    o.position_source = *v == 0 ? PositionSource::kRequest : PositionSource::kCyclic;
  }
  integer(m, "cyclic_period_ms", IntRange::between(1, 1000), o.cyclic_period_ms);
  integer(m, "heartbeat_period_ms", IntRange::between(1, 65535), o.heartbeat_period_ms);
  number(m, "watchdog_timeout_s", Range::greater_than(0.0), o.watchdog_timeout_s);
  number(m, "vel_limit", Range::at_least(0.0), o.vel_limit);
  number(m, "vel_limit_tolerance", Range::at_least(1.0), o.vel_limit_tolerance);
  integer(m, "enable_watchdog_endpoint", IntRange::between(0, 65535), o.enable_watchdog_endpoint);
  integer(m, "watchdog_timeout_endpoint", IntRange::between(0, 65535), o.watchdog_timeout_endpoint);
  m.finish();
}

}  // namespace

std::shared_ptr<const config::DriverSettings> read_can_section(MapReader& m,
                                                               const config::Config& cfg) {
  config::schema::Diagnostics& d = m.diag();
  const std::size_t errors_before = d.messages().size();
  auto s = std::make_shared<CanSettings>();
  if (const auto v = read_string(d, m.take("interface"))) s->interface = *v;
  integer(m, "bitrate", IntRange::between(10'000, 1'000'000), s->bitrate);
  const Field profile = m.take("profile");
  if (!profile.present) m.missing("profile", "cia402 or odrive");
  if (const auto v = read_choice(d, profile, {"cia402", "odrive"})) {
    s->profile = *v == 0 ? Profile::kCia402 : Profile::kOdrive;
  }
  const Field node = m.take("node_id");
  const bool odrive = s->profile == Profile::kOdrive;
  if (const auto v =
          read_integer(d, node, odrive ? IntRange::between(0, 63) : IntRange::between(1, 127))) {
    s->node_id = static_cast<std::uint8_t>(*v);
  }
  const std::string transmission = "the transmission cannot be guessed; see docs/drivers/can.md";
  // Negative for a motor that turns the axis the other way (the direction check says which).
  required_number(m, "torque_per_force", Range::any(), s->torque_per_force, transmission);
  if (s->torque_per_force == 0.0) {
    d.error(m.mark(), m.path() + ".torque_per_force", "must not be 0");
  }
  required_number(m, "position_per_unit", Range::any(), s->position_per_unit, transmission);
  if (s->position_per_unit == 0.0) {
    d.error(m.mark(), m.path() + ".position_per_unit", "must not be 0");
  }
  required_number(m, "max_torque", Range::greater_than(0.0), s->max_torque,
                  "the driver's torque limit in N m");
  integer(m, "sdo_timeout_ms", IntRange::between(1, 10'000), s->sdo_timeout_ms);
  integer(m, "state_timeout_ms", IntRange::between(1, 60'000), s->state_timeout_ms);
  integer(m, "heartbeat_timeout_ms", IntRange::between(1, 65'535), s->heartbeat_timeout_ms);
  integer(m, "tx_full_fault_ticks", IntRange::between(1, 1000), s->tx_full_fault_ticks);
  number(m, "bus_load_warn", Range::interval(0.0, false, 1.0, true), s->bus_load_warn);
  read_cia402(m, !odrive, *s);
  read_odrive(m, odrive, *s);
  const int producer = odrive ? s->odrive.heartbeat_period_ms : s->cia402.heartbeat_producer_ms;
  if (s->heartbeat_timeout_ms <= producer) {
    d.error(m.mark(), m.path() + ".heartbeat_timeout_ms",
            "must be longer than the drive's heartbeat period (" + std::to_string(producer) +
                " ms), or every heartbeat would arrive too late");
  }
  (void)cfg;
  if (d.messages().size() != errors_before) return nullptr;
  return s;
}

const CanSettings& can_settings(const DriverContext& ctx) {
  const auto* s = dynamic_cast<const CanSettings*>(ctx.settings.get());
  if (s == nullptr) throw DeviceError("can: the configuration has no device.can section");
  return *s;
}

int delay_samples(const CanSettings& s, double rate_hz) {
  if (s.profile == Profile::kOdrive && s.odrive.position_source == PositionSource::kCyclic) {
    const double periods = s.odrive.cyclic_period_ms * 1e-3 * rate_hz;
    return std::max(1, static_cast<int>(std::ceil(periods - 1e-9)));
  }
  return 1;
}

int declared_delay(const DriverContext& ctx) {
  return delay_samples(can_settings(ctx), ctx.rate_hz());
}

std::string odrive_speed_note(const CanSettings& s) {
  if (s.profile != Profile::kOdrive || s.odrive.vel_limit <= 0.0) return {};
  const double axis_speed = s.odrive.vel_limit * std::abs(s.position_per_unit);
  char text[512];
  std::snprintf(text, sizeof text,
                "warning: odrive: in torque control the axis brakes by itself above "
                "controller.config.vel_limit = %.3g turn/s (%.3g axis units/s here; "
                "enable_torque_mode_vel_limit) and faults above %.3g times that "
                "(enable_overspeed_error: CONTROLLER_FAILED / OVERSPEED on 0.5, "
                "VELOCITY_LIMIT_VIOLATION on 0.6): forces hapticd never commanded. Raise "
                "vel_limit, or set both to False, then tell hapticd "
                "(device.can.odrive.vel_limit; docs/drivers/can.md)",
                s.odrive.vel_limit, axis_speed, s.odrive.vel_limit_tolerance);
  return text;
}

}  // namespace hapticd::drivers::can
