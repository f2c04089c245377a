// identify's tick loop on the in-process sim device: a realtime run allocates nothing and
// records every tick; every way it ends leaves zero force written and output off.
#include "service/identify_run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "sim/sim_device.h"

namespace hapticd::service {
namespace {

struct Rig {
  Rig() : cfg(free_device()), device(cfg.device, cfg.loop.sample_period_s()) {
    device.configure();
    device.enable();
  }
  static config::Config free_device() {
    config::Config c = config::load_embedded_default();
    c.device.sim.op.kind = config::OperatorSpec::Kind::kNone;
    return c;
  }
  config::Config cfg;
  sim::SimDevice device;
};

std::vector<double> sine(std::size_t n, double amplitude) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = amplitude * std::sin(0.05 * static_cast<double>(k));
  return u;
}

void expect_safe_end(const Rig& rig) {
  EXPECT_EQ(rig.device.last_command(), 0.0);
  EXPECT_FALSE(rig.device.output_enabled());
}

TEST(IdentifyRun, RealtimeRecordsEveryTickWithoutAllocating) {
  Rig rig;
  const std::vector<double> u = sine(200, 1.0);
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  hapticd::testing::AllocationScope scope;
  run_excitation(rig.device, u, 1e-3, true, 0.1, stop, rec);
  EXPECT_EQ(scope.count(), 0u) << "the tick loop allocated";
  EXPECT_EQ(rec.end, ExcitationEnd::kDone);
  EXPECT_EQ(rec.ticks, 200u);
  EXPECT_EQ(rec.start, -0.02);
  EXPECT_GT(rec.travel(), 0.0);
  expect_safe_end(rig);
}

TEST(IdentifyRun, TheTravelGuardEndsItAtZeroForce) {
  Rig rig;
  const std::vector<double> u(2000, 5.0);  // a steady push: the device runs away
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  run_excitation(rig.device, u, 1e-3, false, 0.005, stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kTravel);
  EXPECT_LT(rec.ticks, 2000u);
  EXPECT_LE(rec.travel(), 0.005);
  expect_safe_end(rig);
}

TEST(IdentifyRun, AStopEndsItAtZeroForce) {
  Rig rig;
  const std::vector<double> u = sine(100, 1.0);
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{true};
  run_excitation(rig.device, u, 1e-3, false, 0.1, stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kStopped);
  EXPECT_EQ(rec.ticks, 0u);
  expect_safe_end(rig);
}

TEST(IdentifyRun, ANonFiniteCommandFaultsTheDeviceAndEndsIt) {
  Rig rig;
  std::vector<double> u = sine(100, 1.0);
  u[40] = std::numeric_limits<double>::quiet_NaN();  // the device refuses it: zero written, fault
                                                     // latched
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  run_excitation(rig.device, u, 1e-3, false, 0.1, stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kDeviceFault);
  EXPECT_EQ(rec.ticks, 40u);
  EXPECT_EQ(rig.device.last_command(), 0.0);
  EXPECT_EQ(rig.device.state(), DeviceState::kFaulted);
}

}  // namespace
}  // namespace hapticd::service
