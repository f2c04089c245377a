#include "drivers/can/can_settings.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "base/joints.h"
#include "drivers/can/can_bus_load.h"
#include "drivers/device.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::can {
namespace {

using config::schema::Field;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;

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

// The transmission of one drive, read the same way for the section (every node's default) and
// for each entry of nodes; nothing where the key is absent or wrong.
struct Transmission {
  std::optional<double> torque_per_force;
  std::optional<double> position_per_unit;
  std::optional<double> max_torque;
};

std::optional<double> read_nonzero(MapReader& m, std::string_view key) {
  const Field f = m.take(key);
  const auto v = read_number(m.diag(), f, Range::any());
  if (v && *v == 0.0) {
    m.diag().error(f.key_mark, f.path, "must not be 0");
    return std::nullopt;
  }
  return v;
}

Transmission read_transmission(MapReader& m) {
  Transmission t;
  // Negative for a motor that turns the axis the other way (the direction check says which).
  t.torque_per_force = read_nonzero(m, "torque_per_force");
  t.position_per_unit = read_nonzero(m, "position_per_unit");
  t.max_torque = read_number(m.diag(), m.take("max_torque"), Range::greater_than(0.0));
  return t;
}

// Each setting from the node where it gives one, else from the section; `m` names what
// neither gives (`section_missing`: the section's own error already names it).
void apply_transmission(MapReader& m, const Transmission& own, const Transmission& section,
                        bool report_missing, CanNode& node) {
  const std::string transmission = "the transmission cannot be guessed; see docs/drivers/can.md";
  const auto pick = [&](const std::optional<double>& o, const std::optional<double>& s,
                        std::string_view key, const std::string& why, double& out) {
    if (o) {
      out = *o;
    } else if (s) {
      out = *s;
    } else if (report_missing) {
      m.missing(key, why);
    }
  };
  pick(own.torque_per_force, section.torque_per_force, "torque_per_force", transmission,
       node.torque_per_force);
  pick(own.position_per_unit, section.position_per_unit, "position_per_unit", transmission,
       node.position_per_unit);
  pick(own.max_torque, section.max_torque, "max_torque", "the driver's torque limit in N m",
       node.max_torque);
}

std::optional<std::uint8_t> read_node_id(MapReader& m, const Field& f, bool odrive) {
  const auto v =
      read_integer(m.diag(), f, odrive ? IntRange::between(0, 63) : IntRange::between(1, 127));
  if (!v) return std::nullopt;
  return static_cast<std::uint8_t>(*v);
}

// device.can.nodes: 1..kMaxJoints entries, joint i is entry i. False after reporting problems.
bool read_node_list(MapReader& m, const Field& f, bool odrive, const Transmission& section,
                    std::vector<CanNode>& nodes) {
  config::schema::Diagnostics& d = m.diag();
  const std::string shape = std::string("a list of 1 to ") + std::to_string(base::kMaxJoints) +
                            " nodes, joint i being entry i: [{node_id: 1}, {node_id: 2}]";
  if (!f.node.IsSequence() || f.node.size() == 0 || f.node.size() > base::kMaxJoints) {
    const std::string got = f.node.IsSequence() ? std::to_string(f.node.size()) + " entries"
                                                : config::schema::describe_value(f.node);
    d.error(f.key_mark, f.path, "must be " + shape + ", got " + got);
    return false;
  }
  nodes.clear();
  bool ok = true;
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    const YAML::Node entry = f.node[i];
    const std::string path = f.path + "[" + std::to_string(i) + "]";
    MapReader w(d, Field{path, entry, entry.Mark(), true});
    if (!w.ok()) {
      ok = false;
      continue;
    }
    CanNode node;
    const Field id = w.take("node_id");
    if (!id.present) w.missing("node_id", odrive ? "the axis's node id, 0..63" : "1..127");
    const auto v = read_node_id(w, id, odrive);
    for (std::size_t j = 0; v && j < nodes.size(); ++j) {
      if (nodes[j].node_id != *v) continue;
      d.error(id.key_mark, id.path,
              "node " + std::to_string(*v) + " twice: " + f.path + "[" + std::to_string(j) +
                  "] and " + path + " (each joint needs its own drive)");
      ok = false;
    }
    if (v) node.node_id = *v;
    ok = ok && v.has_value();
    apply_transmission(w, read_transmission(w), section, true, node);
    w.finish();
    nodes.push_back(node);
  }
  return ok;
}

// node_id (one node) or nodes (1..kMaxJoints), never both; each node's transmission.
void read_can_nodes(MapReader& m, bool odrive, std::vector<CanNode>& nodes) {
  const Field id = m.take("node_id");
  const Field list = m.take("nodes");
  const Transmission section = read_transmission(m);
  const bool several = list.present && !list.node.IsNull();
  const bool one = id.present && !id.node.IsNull();
  if (several && one) {
    m.diag().error(list.key_mark, list.path,
                   "refuses " + m.path() +
                       ".node_id beside it: node_id is the one drive of a device of one joint, "
                       "nodes the drives of its joints; give one of them");
    return;
  }
  if (several) {
    read_node_list(m, list, odrive, section, nodes);
    return;
  }
  CanNode& node = nodes.front();
  if (const auto v = one ? read_node_id(m, id, odrive) : std::nullopt) node.node_id = *v;
  apply_transmission(m, {}, section, true, node);
}

// The joints the nodes drive against the mechanism's (the run refuses the device otherwise).
void check_joints(MapReader& m, const CanSettings& s, const config::Config& cfg) {
  const auto joints = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  if (s.nodes.size() == joints) return;
  const std::string n = std::to_string(s.nodes.size());
  m.diag().error(m.mark(), m.path(),
                 n + " node(s) drive " + n + " joint(s), but device.kinematics (" +
                     std::string(kinematics::kind_name(cfg.device.kinematics.kind)) + ") has " +
                     std::to_string(joints) + ": give " + m.path() +
                     ".nodes one node per joint (joint i is nodes[i])");
}

// A bus that cannot carry one tick's frames within one period queues them without end: the
// SYNC and every command come later each tick. Refused with what would fit.
void check_bus_load(MapReader& m, const CanSettings& s, double rate_hz) {
  const BusLoad load = bus_load(s, rate_hz);
  if (load.load <= 1.0) return;
  m.diag().error(m.mark(), m.path(), bus_load_refusal(s, rate_hz, load));
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
  const bool odrive = s->profile == Profile::kOdrive;
  read_can_nodes(m, odrive, s->nodes);
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
  if (d.messages().size() != errors_before) return nullptr;
  // What the whole section decides: the joints the mechanism has, and whether the bus carries
  // one tick's frames of every node within one period.
  check_joints(m, *s, cfg);
  check_bus_load(m, *s, cfg.loop.rate_hz);
  if (d.messages().size() != errors_before) return nullptr;
  return s;
}

CanSettings single_node(const CanSettings& s, std::size_t joint) {
  CanSettings one = s;
  one.nodes = {s.nodes.at(joint)};
  return one;
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
  std::string speeds;  // in each joint's own units
  for (const CanNode& n : s.nodes) {
    char one[64];
    std::snprintf(one, sizeof one, "%s%.3g", speeds.empty() ? "" : ", ",
                  s.odrive.vel_limit * std::abs(n.position_per_unit));
    speeds += one;
    if (s.nodes.size() > 1) speeds += " (node " + std::to_string(n.node_id) + ")";
  }
  char text[512];
  std::snprintf(text, sizeof text,
                "warning: odrive: in torque control the axis brakes by itself above "
                "controller.config.vel_limit = %.3g turn/s (%s axis units/s here; "
                "enable_torque_mode_vel_limit) and faults above %.3g times that "
                "(enable_overspeed_error: CONTROLLER_FAILED / OVERSPEED on 0.5, "
                "VELOCITY_LIMIT_VIOLATION on 0.6): forces hapticd never commanded. Raise "
                "vel_limit, or set both to False, then tell hapticd "
                "(device.can.odrive.vel_limit; docs/drivers/can.md)",
                s.odrive.vel_limit, speeds.c_str(), s.odrive.vel_limit_tolerance);
  return text;
}

}  // namespace hapticd::drivers::can
