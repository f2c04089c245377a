// The conformance suite's allocation case for devices of several joints (conformance_test.cpp
// runs one joint through the one-joint controller): the scene's tick reads and writes every
// joint through the driver, thousands of ticks and then the fault path, and the loop's thread
// allocates nothing.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "control/scene.h"
#include "falcon_image.h"
#include "loop/scene_tick.h"
#include "loop/servo_loop.h"
#include "scene_run.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers {
namespace {

struct JointsCase {
  const char* driver;
  const char* config;  // relative to the source tree
};

const JointsCase kJointsCases[] = {
#if HAPTICD_WITH_HID
    {"hid", "config/hid-report-xy.yaml"},  // two joints in one report each way (issue 37)
    {"hid", "config/hid-pid-xy.yaml"},     // two PID effects, one Set Constant Force each
#endif
    {"sim", "config/sim-delta.yaml"},
#if HAPTICD_WITH_FALCON
    {"falcon", "config/falcon.yaml"},  // three arms, one packet each way a tick (issue 38)
#endif
};

config::Config load_joints(const JointsCase& c) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/" + c.config;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> sets = {config::parse_override("loop.clock=freerun")};
  if (std::string_view(c.driver) == "falcon") {  // the simulated Falcon takes any image
    sets.push_back(
        config::parse_override("device.falcon.firmware=" + hapticd::testing::falcon_test_image()));
  }
  return config::load_config_text(text.str(), path, sets, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

// The scene's loop of `cfg` on `device` for `ticks` ticks; the allocations of its run.
loop::LoopResult run_joints(const config::Config& cfg, Device& device, std::uint64_t ticks,
                            std::uint64_t& allocations) {
  return hapticd::testing::run_scene_loop(cfg, device, ticks, nullptr, &allocations);
}

class JointsConformance : public ::testing::TestWithParam<JointsCase> {};

TEST_P(JointsConformance, ReadAndWriteOfEveryJointNeverAllocate) {
  const config::Config cfg = load_joints(GetParam());
  ASSERT_GT(cfg.walls.size(), 0u) << "a scene of several joints";
  wiring::Loopback pair = wiring::find_driver(cfg.device.driver).make_loopback(cfg);
  sim::PeerRunner runner(*pair.peer);
  sim::PacedDevice device(std::move(pair.device), runner);
  device.configure();
  ASSERT_GT(device.info().joints, 1u);
  device.enable();
  std::uint64_t allocations = 1;
  loop::LoopResult r = run_joints(cfg, device, 3000, allocations);
  EXPECT_EQ(allocations, 0u) << "allocations on the RT path over " << r.ticks << " ticks";
  EXPECT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
  EXPECT_GT(r.count(loop::kCounterContactTicks), 0u) << "the demo presses into a wall";
  if (pair.peer->inject(sim::PeerFault::kDeviceFault)) {
    allocations = 1;
    r = run_joints(cfg, device, 100, allocations);
    EXPECT_EQ(allocations, 0u) << "on the fault path";
    EXPECT_EQ(r.fault.cause, loop::FaultCause::kDeviceReported) << loop::describe(r.fault);
  }
  device.close();
}

std::string joints_case_name(const ::testing::TestParamInfo<JointsCase>& p) {
  return std::string(p.param.driver) + "_" + std::to_string(p.index);
}

INSTANTIATE_TEST_SUITE_P(Drivers, JointsConformance, ::testing::ValuesIn(kJointsCases),
                         joints_case_name);

}  // namespace
}  // namespace hapticd::drivers
