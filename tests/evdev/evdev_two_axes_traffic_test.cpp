// What each way of turning two axes' force into effects sends (docs/drivers/evdev.md, "Two
// axes"), for the same press of config/evdev-joystick.yaml against the simulated joystick:
// the EVIOCSFF the driver makes a tick (its effect_updates), the reports hid-pidff would send
// for those updates by its own rules (pidff_upload_effect: a Set Effect report when
// pidff_needs_set_effect finds the direction changed, a Set Constant Force report when
// pidff_needs_set_constant finds the level changed, per effect; torvalds/linux
// drivers/hid/usbhid/hid-pidff.c), and how far ff-memless's whole degrees turn a direction
// (ml_combine_effects: i = direction * 360 / 0xffff, truncated; drivers/input/ff-memless.c).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>

#include "config/config_loader.h"
#include "control/controller.h"
#include "control/scene.h"
#include "drivers/evdev/evdev_settings.h"
#include "loop/scene_tick.h"
#include "loop/servo_loop.h"
#include "scene_run.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "telemetry/spsc_ring.h"
#include "telemetry/tick_record.h"
#include "wiring/registry.h"

namespace hapticd::drivers::evdev {
namespace {

config::Config traffic_config(const std::string& effect) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/evdev-joystick.yaml");
  std::stringstream s;
  s << in.rdbuf();
  const std::vector<config::Override> o = {config::parse_override("device.evdev.effect=" + effect),
                                           config::parse_override("loop.clock=freerun")};
  return config::load_config_text(s.str(), "evdev-joystick.yaml", o, ".", wiring::driver_schemas());
}

struct Pressed {
  std::vector<std::array<double, 2>> forces;  // each tick's, as written
  std::uint64_t ticks = 0, updates = 0;       // the driver's effect_updates
};

// The example's press, 3000 ticks, each tick's joint forces recorded.
Pressed press(const std::string& effect) {
  const config::Config cfg = traffic_config(effect);
  wiring::Loopback pair = wiring::find_driver("evdev").make_loopback(cfg);
  sim::PeerRunner runner(*pair.peer);
  sim::PacedDevice device(std::move(pair.device), runner);
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  device.configure();
  device.enable();
  const loop::LoopResult r = hapticd::testing::run_scene_loop(cfg, device, 3000, &ring);
  device.disable();
  EXPECT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
  Pressed p;
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  for (const telemetry::TickRecord& t : records) {
    p.forces.push_back({t.force_commanded, t.joint_force[0]});
  }
  p.ticks = records.size();
  for (const base::Counter& c : device.counters()) {
    if (c.name() == "effect_updates") p.updates = c.value();
  }
  device.close();
  return p;
}

// hid-pidff's reports for the updates of one effect whose direction follows the force.
std::uint64_t pidff_directed(const Pressed& p, const EvdevSettings& s) {
  std::uint64_t reports = 0;
  DirectedLevel last{direction_of(s.axis.direction_deg), 0};
  for (const auto& f : p.forces) {
    const DirectedLevel e = directed_level(f[0], f[1], s, last.direction);
    reports += (e.direction != last.direction ? 1 : 0) + (e.level != last.level ? 1 : 0);
    last = e;
  }
  return reports;
}

// And for one effect per axis, each at its fixed direction.
std::uint64_t pidff_per_axis(const Pressed& p, const EvdevSettings& s) {
  std::uint64_t reports = 0;
  std::array<std::int16_t, 2> last{};
  for (const auto& f : p.forces) {
    for (std::size_t j = 0; j < 2; ++j) {
      const std::int16_t level = force_level(f[j], s.force_full_scale);
      reports += level != last[j] ? 1 : 0;
      last[j] = level;
    }
  }
  return reports;
}

TEST(EvdevTwoAxesTraffic, OneEffectWithADirectionSendsLeastForTheSamePress) {
  const Pressed directed = press("direction");
  const Pressed per_axis = press("per_axis");
  const config::Config directed_cfg = traffic_config("direction");  // owns the settings
  const EvdevSettings& s = evdev_settings(directed_cfg);
  ASSERT_GT(directed.ticks, 2000u);
  // One EVIOCSFF a tick against two, and the zeros of enable, of the loop's last write and of
  // disable.
  EXPECT_EQ(directed.updates, directed.ticks + 3);
  EXPECT_EQ(per_axis.updates, 2 * (per_axis.ticks + 3));
  const std::uint64_t pidff_one = pidff_directed(directed, s);
  const std::uint64_t pidff_two = pidff_per_axis(directed, s);
  std::cout << "the press, " << directed.ticks << " ticks: EVIOCSFF " << directed.updates
            << " (direction) and " << per_axis.updates << " (per_axis); hid-pidff's reports for "
            << "the same forces: " << pidff_one << " (direction), " << pidff_two << " (per_axis)\n";
  RecordProperty("pidff_reports_direction", std::to_string(pidff_one));
  RecordProperty("pidff_reports_per_axis", std::to_string(pidff_two));
  EXPECT_LT(pidff_one, pidff_two) << "the force along one wall's normal keeps its direction";
}

// ff-memless turns the direction into whole degrees, truncated: up to a degree off across the
// force; at the four directions of the axes it is exact.
TEST(EvdevTwoAxesTraffic, FfMemlessTurnsADirectionUpToADegree) {
  double worst = 0.0;
  for (int d = 0; d < 0x10000; ++d) {
    const int degrees = d * 360 / 0xffff;  // ml_combine_effects' i
    const double off = d / 65536.0 * 360.0 - degrees;
    worst = std::max(worst, std::abs(off));
  }
  const double across = std::sin(worst * std::numbers::pi / 180.0);
  std::cout << "ff-memless: a direction up to " << worst << " degrees off, " << across * 100
            << " % of the force across it\n";
  EXPECT_GT(across, 0.015);
  EXPECT_LT(across, 0.018);
  for (const int d : {0x0000, 0x4000, 0x8000, 0xC000}) {
    EXPECT_NEAR(d * 360 / 0xffff, d / 65536.0 * 360.0, 1e-9) << "exact along an axis: " << d;
  }
}

}  // namespace
}  // namespace hapticd::drivers::evdev
