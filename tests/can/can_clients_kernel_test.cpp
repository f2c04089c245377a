// The scene interface's examples (examples/python, examples/cpp; docs/clients.md) against
// `hapticd run` on reference devices in the kernel test machine: two ODrive 0.5 axes on vcan0
// as the joints of an XY gantry (config/can-gantry.yaml), a movable wall across x. Each example
// is run and checked as on the simulated delta (tests/python/example_runs.py): a too-stiff wall
// refused with the gate's code, a box added and removed, every tick read from the state block,
// a wall moved by a sine at 100 Hz with every move applied. The loop runs at the rig's 50 Hz
// (an emulated guest keeps no 1 kHz), so the latencies printed measure the emulator.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "child_process.h"
#include "reference/can/odrive_056.h"
#include "reference_kernel_rig.h"
#include "vcan_interface.h"

namespace hapticd::drivers::can::testing {
namespace {

TEST(CanClientsOnVcan, ThePythonAndCppExamplesRunAgainstAGantryOfReferenceAxes) {
  kernel_test::VcanInterface bus("vcan0");
  OdriveGantryAxes gantry(kOdriveRig.hand_force);
  auto& axes = gantry.axes;
  const std::string socket = "/tmp/hapticd-kt-clients.sock";
  std::vector<std::string> a = gantry_args(kOdriveRig, odrive_gantry_sets());
  *(std::find(a.begin(), a.end(), "--duration") + 1) = "600";  // the examples' time, and slack
  // Later --set wins: one wall across x, out of the axes' way, that clients may move, soft
  // enough at 50 Hz to share the x axis's damping with a face of the box (K 20 each).
  a.insert(a.end(),
           {"--set", "walls=[{point: [0.05, 0], normal: [1, 0], damping: 0, stiffness: 20}]",
            "--socket", socket});
  ChildProcess run(a, "/tmp/hapticd-kt-clients.out");
  kernel_test::wait_until([&] { return axes[0]->armed() && axes[1]->armed(); },
                          milliseconds(60'000), "both axes in closed loop");
  ChildProcess examples(
      {"/usr/bin/python3",
       std::string(HAPTICD_SOURCE_DIR) + "/tests/client_examples/against_daemon.py", "--socket",
       socket, "--source-dir", HAPTICD_SOURCE_DIR, "--cpp-dir", HAPTICD_EXAMPLES_CPP_DIR,
       "--rate-hz", std::to_string(kOdriveRig.rate_hz), "--axes", "2", "--box-stiffness", "20"},
      "/tmp/hapticd-kt-clients-examples.out");
  EXPECT_EQ(examples.wait(seconds(500)), 0) << examples.output() << "\nhapticd:\n" << run.output();
  run.signal(SIGTERM);
  EXPECT_EQ(run.wait(seconds(60)), 0) << run.output();
  kernel_test::wait_until([&] { return !axes[0]->armed() && !axes[1]->armed(); },
                          milliseconds(3000), "both axes idle after the stop");
  for (auto& r : gantry.runners) r->stop();
  EXPECT_EQ(axes[0]->motor_force_n(), 0.0);
  EXPECT_EQ(axes[1]->motor_force_n(), 0.0);
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
