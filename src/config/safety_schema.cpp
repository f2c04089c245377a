// The section `safety`: the gate's mode and margin, the sample checks, the passivity observer,
// the direction check and the runaway guard (config/sim.yaml documents each key).
#include <climits>
#include <cstdint>

#include "config/config_schema.h"

namespace hapticd::config::schema {
namespace {

const Options<GateMode> kGates{
    {"enforce", GateMode::kEnforce}, {"warn", GateMode::kWarn}, {"derate", GateMode::kDerate}};
const Options<PassivityControl> kPassivityControls{{"off", PassivityControl::kOff},
                                                   {"observe", PassivityControl::kObserve},
                                                   {"damp", PassivityControl::kDamp}};
const Options<DirectionCheckMode> kDirectionModes{{"enforce", DirectionCheckMode::kEnforce},
                                                  {"off", DirectionCheckMode::kOff}};
const Options<ClientWalls> kClientWalls{{"remove", ClientWalls::kRemove},
                                        {"keep", ClientWalls::kKeep}};
const Options<NoMotionAction> kNoMotionActions{{"refuse", NoMotionAction::kRefuse},
                                               {"run", NoMotionAction::kRun}};

void read_direction_check(MapReader& safety, DirectionCheckConfig& c) {
  MapReader m(safety.diag(), safety.take("direction_check"));
  if (const auto v = choice(m.diag(), m.take("mode"), kDirectionModes)) c.mode = *v;
  // Half of max_force is no longer a probe: it is a push a hand would feel as a kick.
  number(m, "level", Range::interval(0.0, false, 0.5, true), c.level);
  number(m, "duration_ms", Range::interval(0.0, false, 1000.0, true), c.duration_ms);
  number(m, "min_motion", Range::interval(0.0, false, 1.0, true), c.min_motion);
  if (const auto v = choice(m.diag(), m.take("on_no_motion"), kNoMotionActions)) {
    c.on_no_motion = *v;
  }
  number(m, "rest_timeout_ms", Range::interval(0.0, false, 60000.0, true), c.rest_timeout_ms);
  number(m, "max_latency_ms", Range::interval(0.0, true, 1000.0, true), c.max_latency_ms);
  m.finish();
}

}  // namespace

void read_safety(MapReader& top, SafetyConfig& safety) {
  MapReader m(top.diag(), top.take("safety"));
  if (const auto v = choice(m.diag(), m.take("gate"), kGates)) safety.gate = *v;
  number(m, "operator_passivity_shortage", Range::at_least(0.0),
         safety.operator_passivity_shortage);
  number(m, "passivity_margin", Range::interval(0.0, true, 1.0, false), safety.passivity_margin);
  number(m, "max_speed", Range::greater_than(0.0), safety.max_speed);
  number(m, "max_wall_speed", Range::greater_than(0.0), safety.max_wall_speed);
  if (const auto v = choice(m.diag(), m.take("client_walls_on_leave"), kClientWalls)) {
    safety.client_walls_on_leave = *v;
  }
  number(m, "client_force_limit", Range::at_least(0.0), safety.client_force_limit);
  number(m, "client_force_hold_ms", Range::interval(0.0, false, 10000.0, true),
         safety.client_force_hold_ms);
  number(m, "client_force_ramp_ms", Range::interval(0.0, false, 10000.0, true),
         safety.client_force_ramp_ms);
  number(m, "client_force_energy_j", Range::greater_than(0.0), safety.client_force_energy_j);
  integer(m, "stale_fault_ticks", IntRange::at_least(1, INT_MAX), safety.stale_fault_ticks);
  if (const auto v =
          read_integer(m.diag(), m.take("sequence_gap_fault"), IntRange::between(0, 65535))) {
    safety.sequence_gap_fault = static_cast<std::uint32_t>(*v);
  }
  if (const auto v = choice(m.diag(), m.take("passivity_controller"), kPassivityControls)) {
    safety.passivity_controller = *v;
  }
  number(m, "passivity_max_damping", Range::greater_than(0.0), safety.passivity_max_damping);
  read_direction_check(m, safety.direction_check);
  number(m, "max_penetration", Range::at_least(0.0), safety.max_penetration);
  m.finish();
}

}  // namespace hapticd::config::schema
