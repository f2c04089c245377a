// Helpers shared by the config tests: run a load that must fail and return its messages, and
// compare two Configs field by field (Config has no operator==).
#pragma once

#include <gtest/gtest.h>

#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "config/config_loader.h"

namespace hapticd::config::testing {

inline std::vector<Override> sets(std::initializer_list<std::string_view> args) {
  std::vector<Override> out;
  for (std::string_view a : args) out.push_back(parse_override(a));
  return out;
}

// The messages of the ConfigError that loading `yaml` (source name "t.yaml") must throw.
inline std::vector<std::string> errors_of(std::string_view yaml,
                                          const std::vector<Override>& overrides = {}) {
  try {
    load_config_text(yaml, "t.yaml", overrides);
  } catch (const ConfigError& e) {
    return e.messages();
  }
  ADD_FAILURE() << "loading did not fail:\n" << yaml;
  return {};
}

using Lines = std::vector<std::string>;

inline void expect_same_profile(const ProfileSpec& a, const ProfileSpec& b) {
  EXPECT_EQ(a.shape, b.shape);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].t_s, b.points[i].t_s) << i;
    EXPECT_EQ(a.points[i].value, b.points[i].value) << i;
  }
  EXPECT_EQ(a.offset, b.offset);
  EXPECT_EQ(a.amplitude, b.amplitude);
  EXPECT_EQ(a.frequency_hz, b.frequency_hz);
  EXPECT_EQ(a.phase_rad, b.phase_rad);
}

// Every typed value (not source_name / effective_yaml, which say where it came from).
inline void expect_same_values(const Config& a, const Config& b) {
  EXPECT_EQ(a.loop.rate_hz, b.loop.rate_hz);
  EXPECT_EQ(a.loop.clock, b.loop.clock);
  EXPECT_EQ(a.loop.rt_priority, b.loop.rt_priority);
  EXPECT_EQ(a.loop.cpu, b.loop.cpu);
  EXPECT_EQ(a.loop.overrun_fault_streak, b.loop.overrun_fault_streak);
  EXPECT_EQ(a.device.driver, b.device.driver);
  EXPECT_EQ(a.device.mass, b.device.mass);
  EXPECT_EQ(a.device.damping, b.device.damping);
  EXPECT_EQ(a.device.max_force, b.device.max_force);
  const SimDeviceConfig& sa = a.device.sim;
  const SimDeviceConfig& sb = b.device.sim;
  EXPECT_EQ(sa.counts_per_unit, sb.counts_per_unit);
  EXPECT_EQ(sa.noise_counts, sb.noise_counts);
  EXPECT_EQ(sa.seed, sb.seed);
  EXPECT_EQ(sa.initial_position, sb.initial_position);
  EXPECT_EQ(sa.initial_velocity, sb.initial_velocity);
  EXPECT_EQ(sa.op.kind, sb.op.kind);
  EXPECT_EQ(sa.op.stiffness, sb.op.stiffness);
  EXPECT_EQ(sa.op.damping, sb.op.damping);
  expect_same_profile(sa.op.setpoint, sb.op.setpoint);
  expect_same_profile(sa.op.force, sb.op.force);
  EXPECT_EQ(sa.op.motion.offset, sb.op.motion.offset);
  EXPECT_EQ(sa.op.motion.amplitude, sb.op.motion.amplitude);
  EXPECT_EQ(sa.op.motion.frequency_hz, sb.op.motion.frequency_hz);
  EXPECT_EQ(sa.op.motion.phase_rad, sb.op.motion.phase_rad);
  EXPECT_EQ(sa.op.replay_log, sb.op.replay_log);
  EXPECT_EQ(a.wall.position, b.wall.position);
  EXPECT_EQ(a.wall.normal, b.wall.normal);
  EXPECT_EQ(a.wall.stiffness, b.wall.stiffness);
  EXPECT_EQ(a.wall.damping, b.wall.damping);
  EXPECT_EQ(a.wall.discretization, b.wall.discretization);
  EXPECT_EQ(a.wall.delay_samples, b.wall.delay_samples);
  EXPECT_EQ(a.wall.no_pull, b.wall.no_pull);
  EXPECT_EQ(a.wall.coupling.present, b.wall.coupling.present);
  EXPECT_EQ(a.wall.coupling.numerator, b.wall.coupling.numerator);
  EXPECT_EQ(a.wall.coupling.denominator, b.wall.coupling.denominator);
  EXPECT_EQ(a.safety.gate, b.safety.gate);
  EXPECT_EQ(a.safety.operator_passivity_shortage, b.safety.operator_passivity_shortage);
  EXPECT_EQ(a.safety.passivity_margin, b.safety.passivity_margin);
  EXPECT_EQ(a.safety.max_speed, b.safety.max_speed);
  EXPECT_EQ(a.analysis.operator_stiffness, b.analysis.operator_stiffness);
  EXPECT_EQ(a.analysis.operator_damping, b.analysis.operator_damping);
  EXPECT_EQ(a.analysis.transparency_weight_numerator, b.analysis.transparency_weight_numerator);
  EXPECT_EQ(a.analysis.transparency_weight_denominator, b.analysis.transparency_weight_denominator);
  EXPECT_EQ(a.telemetry.log_path, b.telemetry.log_path);
  EXPECT_EQ(a.telemetry.ring_capacity, b.telemetry.ring_capacity);
}

}  // namespace hapticd::config::testing
