// The section device.sim: the simulated plant (the sim driver's, and every loopback peer's) and
// what acts on it besides the motor, its operator. On a device of several joints the operator
// has its place in task space (docs/kinematics.md, the simulated mechanism).
#include <algorithm>
#include <climits>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "config/config_schema.h"

namespace hapticd::config::schema {
namespace {

using Kind = OperatorSpec::Kind;
const Options<Kind> kKinds{{"hand", Kind::kHand},
                           {"force", Kind::kForce},
                           {"motion", Kind::kMotion},
                           {"replay", Kind::kReplay}};

const std::vector<std::string> kOperatorKeys{"kind",  "stiffness", "damping",   "setpoint",
                                             "force", "offset",    "amplitude", "frequency_hz",
                                             "phase", "log",       "origin",    "direction"};

// The keys of `kind`; on several task axes a hand or none also has its place in task space.
std::vector<std::string> operator_keys_of(Kind kind, int task_axes) {
  if (task_axes > 1 && kind == Kind::kNone) return {"kind", "origin"};
  if (task_axes > 1 && kind == Kind::kHand) {
    return {"kind", "stiffness", "damping", "setpoint", "origin", "direction"};
  }
  switch (kind) {
    case Kind::kForce:
      return {"kind", "force"};
    case Kind::kMotion:
      return {"kind", "offset", "amplitude", "frequency_hz", "phase"};
    case Kind::kReplay:
      return {"kind", "log"};
    case Kind::kHand:
    case Kind::kNone:
      break;
  }
  return {"kind", "stiffness", "damping", "setpoint"};
}

std::string resolve_path(const std::string& path, const std::string& base_dir) {
  namespace fs = std::filesystem;
  fs::path p(path);
  if (p.is_relative()) p = fs::path(base_dir) / p;
  std::error_code ec;
  const fs::path absolute = fs::absolute(p, ec);
  return (ec ? p : absolute).lexically_normal().string();
}

// Imposed motion: x = offset + amplitude cos(2 pi f t + phase), sampled at rate_hz, so f
// above Nyquist would alias into a different motion than the one written.
void read_motion(MapReader& m, const std::string& reason, std::optional<double> rate_hz,
                 MotionSpec& out) {
  Diagnostics& d = m.diag();
  MotionSpec spec;
  bool ok = true;
  auto required = [&](std::string_view key, const Range& range, double& target) {
    const Field f = m.take(key);
    if (!f.present) {
      m.missing(key, "required by " + reason);
      ok = false;
    } else if (const auto v = read_number(d, f, range)) {
      target = *v;
    } else {
      ok = false;
    }
    return f;
  };
  required("offset", Range::any(), spec.offset);
  required("amplitude", Range::any(), spec.amplitude);
  const Field freq = required("frequency_hz", Range::greater_than(0.0), spec.frequency_hz);
  if (ok && rate_hz && spec.frequency_hz > *rate_hz / 2.0) {
    d.error(freq.key_mark, freq.path,
            "must be <= the Nyquist frequency rate_hz/2 = " + format_number(*rate_hz / 2.0) +
                ", got '" + freq.node.Scalar() + "'");
    ok = false;
  }
  spec.phase_rad = read_number(d, m.take("phase")).value_or(0.0);
  if (ok) out = spec;
}

// A hand or none on several task axes: where the device starts, and which way the hand's
// set-point moves (a hand needs one). Another kind drives one joint and is refused.
void read_task_operator(MapReader& m, const Field& kind_field, Kind kind,
                        const kinematics::Kinematics& k, OperatorSpec& op) {
  Diagnostics& d = m.diag();
  const int n = kinematics::joint_count(k);
  if (kind != Kind::kHand && kind != Kind::kNone) {
    d.error(kind_field.key_mark, kind_field.path,
            "drives one joint; a device of " + std::to_string(n) +
                " joints (device.kinematics) takes 'hand' or 'none'");
    return;
  }
  const Field origin = m.take("origin");
  if (origin.present && read_fixed_numbers(
                            m, origin, n, [](double, const Range&) { return true; }, Range::any(),
                            "", op.origin.data(), "numbers (one per task axis)")) {
    const kinematics::Status st = kinematics::inverse(k, op.origin).status;
    if (st != kinematics::Status::kOk) {
      d.error(origin.key_mark, origin.path,
              std::string("is not a pose of the mechanism: ") + kinematics::status_name(st));
    }
  }
  if (kind != Kind::kHand) return;
  const Field dir = m.take("direction");
  if (!dir.present) {
    m.missing("direction", "a hand on several task axes pushes along it");
  } else if (read_fixed_numbers(
                 m, dir, n, [](double, const Range&) { return true; }, Range::any(), "",
                 op.direction.data(), "numbers (one per task axis)")) {
    unit_direction(d, dir, "the way the hand's set-point moves", op.direction);
  }
}

void read_operator(MapReader& sim, std::optional<double> rate_hz, const std::string& base_dir,
                   const kinematics::Kinematics& mechanism, OperatorSpec& op) {
  const Field field = sim.take("operator");
  // Absent: the defaults of OperatorSpec stand.
  if (!field.present) return;
  MapReader m(sim.diag(), field);
  if (!m.ok()) return;
  Diagnostics& d = m.diag();

  const Field kind_field = m.take("kind");
  Kind kind = Kind::kHand;
  if (kind_field.present) {
    const auto k = choice(d, kind_field, kKinds);
    if (!k) {
      m.skip_rest();  // which keys apply depends on the kind just reported as wrong
      return;
    }
    kind = *k;
  }
  op.kind = kind;
  const std::string reason = "operator kind '" + name_of(kKinds, kind) + "'";

  switch (kind) {
    case Kind::kHand:
      number(m, "stiffness", Range::greater_than(0.0), op.stiffness);
      number(m, "damping", Range::at_least(0.0), op.damping);
      read_profile(m, "setpoint", reason, op.setpoint);
      break;
    case Kind::kForce:
      read_profile(m, "force", reason, op.force);
      break;
    case Kind::kMotion:
      read_motion(m, reason, rate_hz, op.motion);
      break;
    case Kind::kReplay: {
      const Field log = m.take("log");
      if (!log.present) {
        m.missing("log", "required by " + reason);
      } else if (const auto path = read_string(d, log)) {
        if (path->empty()) {
          d.error(log.key_mark, log.path, "must be the path of a tick log, got nothing");
        } else {
          op.replay_log = resolve_path(*path, base_dir);
        }
      }
      break;
    }
    case Kind::kNone:
      break;
  }
  const int task_axes = kinematics::joint_count(mechanism);
  if (task_axes > 1) read_task_operator(m, kind_field, kind, mechanism, op);
  const std::vector<std::string> used = operator_keys_of(kind, task_axes);
  for (const std::string& key : kOperatorKeys) {
    if (std::find(used.begin(), used.end(), key) == used.end()) m.not_used(key, reason);
  }
  m.finish();
}

}  // namespace

void read_plant(MapReader& device, std::optional<double> rate_hz, const std::string& base_dir,
                const kinematics::Kinematics& k, SimDeviceConfig& sim_cfg) {
  MapReader sim(device.diag(), device.take("sim"));
  Diagnostics& d = sim.diag();
  number(sim, "counts_per_unit", Range::at_least(0.0), sim_cfg.counts_per_unit);
  number(sim, "noise_counts", Range::at_least(0.0), sim_cfg.noise_counts);
  if (const auto v = read_integer(d, sim.take("seed"), IntRange::at_least(0, LLONG_MAX))) {
    sim_cfg.seed = static_cast<std::uint64_t>(*v);
  }
  if (kinematics::joint_count(k) > 1) {
    // Several joints start at rest at the operator's origin (in task space).
    sim_cfg.op.origin = kinematics::workspace_centre(k);
    for (const char* key : {"initial_position", "initial_velocity"}) {
      sim.not_used(key, "a device of several joints (it starts at rest at operator.origin)");
    }
  } else {
    number(sim, "initial_position", Range::any(), sim_cfg.initial_position);
    number(sim, "initial_velocity", Range::any(), sim_cfg.initial_velocity);
  }
  if (const auto v = read_bool(d, sim.take("force_reversed"))) sim_cfg.force_reversed = *v;
  read_operator(sim, rate_hz, base_dir, k, sim_cfg.op);
  sim.finish();
}

}  // namespace hapticd::config::schema
