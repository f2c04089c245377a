// `hapticd identify` as a user runs it: against the sim and every loopback peer this build
// has, with the example configurations' encoder quantisation, it must recover the configured
// m and b within 1 %; and it refuses what it must refuse.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

void expect_recovers(const std::vector<std::string>& args, double mass, double damping) {
  std::vector<std::string> cmd = {hapticd_binary(), "identify", "--json"};
  cmd.insert(cmd.end(), args.begin(), args.end());
  const ProcessResult r = run_process(cmd);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const json j = json::parse(r.out);
  EXPECT_NEAR(j["mass"].get<double>(), mass, 0.01 * mass) << r.out;
  EXPECT_NEAR(j["damping"].get<double>(), damping, 0.01 * damping) << r.out;
  EXPECT_LT(j["mass_ci95"].get<double>(), 0.01 * mass);
  EXPECT_LT(j["damping_ci95"].get<double>(), 0.01 * damping);
  EXPECT_GT(j["travel_m"].get<double>(), 0.001) << "it really moved the device";
  EXPECT_LT(j["travel_m"].get<double>(), 0.1);
}

TEST(CliIdentify, RecoversTheSimsMassAndDamping) {
  expect_recovers({"--config", example("sim.yaml")}, 0.1, 2.0);
  // Not the defaults by accident: another device, and the operator of the config ignored.
  expect_recovers({"--set", "device.mass=0.35", "--set", "device.damping=0.9"}, 0.35, 0.9);
}

TEST(CliIdentify, PrintsTheEstimatesAndTheYamlToPaste) {
  const ProcessResult r = run_process({hapticd_binary(), "identify"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "simulated device held free: no operator")) << r.out;
  EXPECT_TRUE(has(r.out, "kg (95 % interval)")) << r.out;
  const auto yaml = r.out.find("paste into the configuration:\ndevice:\n  mass: ");
  ASSERT_NE(yaml, std::string::npos) << r.out;
  const std::string lines = r.out.substr(yaml);
  const double mass = std::stod(lines.substr(lines.find("mass: ") + 6));
  const double damping = std::stod(lines.substr(lines.find("damping: ") + 9));
  EXPECT_NEAR(mass, 0.1, 1e-3);
  EXPECT_NEAR(damping, 2.0, 0.02);
}

// A gantry of two different axes: --joint J excites J alone (the others commanded zero) and
// recovers its own m and b, and the YAML to paste keeps the other joint's as configured.
TEST(CliIdentify, RecoversEachJointOfSeveralWithItsOwnMassAndDamping) {
  const std::string config = temp_path("gantry.yaml");
  std::ofstream(config) << R"(device:
  mass: [0.1, 0.4]
  damping: [2, 5]
  kinematics: {kind: cartesian, joints: 2}
walls:
  - {point: [0.05, 0], normal: [1, 0], stiffness: 500}
)";
  expect_recovers({"--config", config, "--joint", "0"}, 0.1, 2.0);
  expect_recovers({"--config", config, "--joint", "1"}, 0.4, 5.0);
  const ProcessResult r =
      run_process({hapticd_binary(), "identify", "--config", config, "--joint", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "joint 1 excited, the others commanded zero")) << r.out;
  EXPECT_TRUE(has(r.out, "  mass: [0.1, 0.4")) << r.out;
  EXPECT_TRUE(has(r.out, "  damping: [2, 5") || has(r.out, "  damping: [2, 4.9")) << r.out;
  const ProcessResult bad =
      run_process({hapticd_binary(), "identify", "--config", config, "--joint", "2"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_TRUE(has(bad.err,
                  "--joint: must be 0 to 1 (device.kinematics (kind cartesian) has 2 "
                  "joints), got 2"))
      << bad.err;
}

#if HAPTICD_TEST_WITH_HID
TEST(CliIdentify, RecoversThroughTheHidReportPeer) {
  expect_recovers({"--loopback", "--config", example("hid-report.yaml")}, 0.1, 2.0);
}
TEST(CliIdentify, RecoversThroughTheHidPidPeer) {
  expect_recovers({"--loopback", "--config", example("hid-pid.yaml")}, 0.1, 2.0);
}
#endif
#if HAPTICD_TEST_WITH_CAN
TEST(CliIdentify, RecoversThroughTheCia402Peer) {
  expect_recovers({"--loopback", "--config", example("can-cia402.yaml")}, 0.1, 2.0);
}
TEST(CliIdentify, RecoversThroughTheOdrivePeer) {
  expect_recovers({"--loopback", "--config", example("can-odrive.yaml")}, 0.1, 2.0);
}
#endif
#if HAPTICD_TEST_WITH_GPIO
TEST(CliIdentify, RecoversThroughTheGpioPeer) {
  expect_recovers({"--loopback", "--config", example("gpio.yaml")}, 0.1, 2.0);
}
#endif
#if HAPTICD_TEST_WITH_EVDEV
TEST(CliIdentify, RecoversThroughTheEvdevPeer) {
  expect_recovers({"--loopback", "--config", example("evdev.yaml")}, 0.1, 2.0);
}
#endif

#if HAPTICD_TEST_WITH_HID || HAPTICD_TEST_WITH_CAN || HAPTICD_TEST_WITH_GPIO
TEST(CliIdentify, RefusesARealDriverWithoutBeingToldTheDeviceIsFree) {
  const std::string config = example(HAPTICD_TEST_WITH_HID   ? "hid-report.yaml"
                                     : HAPTICD_TEST_WITH_CAN ? "can-odrive.yaml"
                                                             : "gpio.yaml");
  const ProcessResult r = run_process({hapticd_binary(), "identify", "--config", config});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_TRUE(has(r.err, "--yes-the-device-is-free")) << r.err;
  EXPECT_TRUE(r.out.empty());
}
#endif

TEST(CliIdentify, RefusesAnExcitationOutsideTheDevice) {
  ProcessResult r = run_process({hapticd_binary(), "identify", "--amplitude", "12"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r.err, "--amplitude: must be > 0 and at most device.max_force = 10 N, got 12"))
      << r.err;
  r = run_process({hapticd_binary(), "identify", "--f-high", "600"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r.err, "--f-high: must be below the Nyquist frequency 500 Hz")) << r.err;
  r = run_process({hapticd_binary(), "identify", "--duration", "nan"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  r = run_process({hapticd_binary(), "identify", "--f-low", "0.01"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r.err, "--f-low: must be at least one cycle over --duration")) << r.err;
}

TEST(CliIdentify, ADeviceThatWandersTooFarStopsAsAFaultWithZeroForce) {
  const ProcessResult r =
      run_process({hapticd_binary(), "identify", "--amplitude", "4", "--max-travel", "0.002"});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_TRUE(has(r.err, "moved more than --max-travel 0.002 m")) << r.err;
  EXPECT_TRUE(has(r.err, "zero force commanded, output disabled")) << r.err;
  EXPECT_TRUE(r.out.empty());
}

}  // namespace
}  // namespace hapticd::testing
