// The pid profile against the simulated device as a USB device of its own (the raw gadget on
// dummy_hcd, sim/peers/hid/raw_gadget_peer.h), in the kernel test machine: usbhid, hidraw and
// libusb meet it as hardware, and its control endpoint answers the PID feature reports
// (Create New Effect, Block Load, Device Gain), which Linux 6.1's f_hid cannot. And once
// through uhid, the lighter way to a hidraw device.
#include <gtest/gtest.h>

#include "kernel_rig.h"

namespace hapticd::drivers::hid {
namespace {

using namespace testing;

// The simulated PID device on `endpoint`, listed by hidraw before the test goes on; gone
// again (unplugged, and no longer listed) when the rig ends, so the next rig's device is not
// mistaken for it.
struct PidRig {
  PidRig(const char* backend, const char* endpoint, std::vector<std::string> more = {})
      : sets(sets_for(backend, std::move(more))),
        cfg(load_example("hid-pid.yaml", sets)),
        peer(std::make_unique<KernelPeer>(cfg, endpoint)) {
    EXPECT_TRUE(wait_listed(true)) << "the device never appeared on " << endpoint;
  }
  ~PidRig() {
    peer.reset();
    EXPECT_TRUE(wait_listed(false)) << "the device did not go";
  }
  sim::LoopbackPeer& device() { return *peer->peer; }
  std::vector<std::string> sets;
  config::Config cfg;
  std::unique_ptr<KernelPeer> peer;
};

constexpr const char* kRawGadget = "/dev/raw-gadget";

class HidPidUsb : public ::testing::TestWithParam<const char*> {};

TEST_P(HidPidUsb, PidProfileRendersTheSimDriversWall) {
  // The simulated firmware drops its output when the host is silent for longer than the
  // effect's duration (100 ms in hid-pid.yaml). The first `hapticd run` in the machine can be
  // silent that long between enable and its first tick (mlockall and prefaulting read the
  // binary over 9p in an emulated guest), so the wall is measured with a 1 s effect.
  PidRig rig(GetParam(), kRawGadget, {"device.hid.pid.effect_duration_ms=1000"});
  expect_the_sim_drivers_wall("hid-pid.yaml", rig.sets, rig.device());
}

TEST_P(HidPidUsb, APeerThatStopsAnsweringFaultsWithZeroForce) {
  PidRig rig(GetParam(), kRawGadget, {"device.hid.pid.effect_duration_ms=1000"});
  expect_fault_exit("hid-pid.yaml", rig.sets, rig.device(), sim::PeerFault::kStopAnswering,
                    "stale encoder data");
}

TEST_P(HidPidUsb, ASafetySwitchOffFaultsWithZeroForce) {
  // The simulated device drives its Safety Switch: this configuration faults on it (0x04).
  // A 1 s effect: the firmware's own watchdog must not trip first (the emulator may leave the
  // host silent for 100 ms between the enable and the first tick).
  PidRig rig(GetParam(), kRawGadget,
             {"device.hid.pid.fault_mask=0x06", "device.hid.pid.effect_duration_ms=1000"});
  expect_fault_exit("hid-pid.yaml", rig.sets, rig.device(), sim::PeerFault::kDeviceFault,
                    "the device reports actuators disabled, safety switch off");
}

TEST_P(HidPidUsb, SkippedSequenceNumbersFaultWithZeroForce) {
  PidRig rig(GetParam(), kRawGadget,
             {"device.hid.pid.effect_duration_ms=1000",
              "device.hid.pid.sequence={usage_page: 0xff00, usage: 0x20}"});
  expect_fault_exit("hid-pid.yaml", rig.sets, rig.device(), sim::PeerFault::kSkipSequence,
                    "sequence skipped 5[0-9] samples");
}

// Without hapticd the effect runs out: the device's own duration is the watchdog. A 1 s
// effect (as above): with hid-pid.yaml's 100 ms, a stall of the emulated machine during the
// direction check's push lets the push run out, and the check rightly refuses the device.
TEST_P(HidPidUsb, AKilledHapticdLeavesNoForceBehindThroughTheEffectsDuration) {
  PidRig rig(GetParam(), kRawGadget, {"device.hid.pid.effect_duration_ms=1000"});
  expect_no_force_after_sigkill("hid-pid.yaml", rig.sets, rig.device(), std::chrono::seconds(2));
}

// Unplugged mid-run: the raw gadget released, the host sees a disconnect.
TEST_P(HidPidUsb, AnUnpluggedDeviceFaultsTheRun) {
  PidRig rig(GetParam(), kRawGadget,
             {"device.hid.pid.effect_duration_ms=1000", "safety.stale_fault_ticks=1000"});
  const Hapticd h = run_hapticd(
      with_sets({"run", "--config", example("hid-pid.yaml"), "--duration", "30"},
                unchecked(rig.sets)),
      [&](pid_t) {
        ASSERT_TRUE(reference::wait_armed()) << "the direction check never armed the wall";
        ASSERT_TRUE(KernelPeer::wait_for([&] { return rig.device().applied_force() < -0.2; }));
        ASSERT_TRUE(rig.device().inject(sim::PeerFault::kTransportFault));
      });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_NE(faults(h).find("hid: the device is gone"), std::string::npos) << faults(h) << "\n"
                                                                          << h.log;
}

INSTANTIATE_TEST_SUITE_P(Backends, HidPidUsb, ::testing::Values("hidraw", "libusb"),
                         [](const auto& p) { return std::string(p.param); });

// uhid has no USB underneath: hidraw only.
TEST(HidPidUhid, PidProfileRendersTheSimDriversWall) {
  PidRig rig("hidraw", "/dev/uhid", {"device.hid.pid.effect_duration_ms=1000"});
  expect_the_sim_drivers_wall("hid-pid.yaml", rig.sets, rig.device());
}

}  // namespace
}  // namespace hapticd::drivers::hid
