// The report profile against the simulated device on a USB HID gadget (configfs f_hid on
// dummy_hcd), in the kernel test machine (tools/kernel-vm): usbhid, hidraw and libusb meet it
// exactly as hardware on a cable. `hapticd run` runs as a person runs it, in its own process;
// the simulated device runs in this one, so faults can be injected mid-run.
#include <gtest/gtest.h>

#include "drivers/hid/descriptor_builder.h"
#include "kernel_rig.h"
#include "usb_hid_gadget.h"

namespace hapticd::drivers::hid {
namespace {

using namespace testing;

kernel_test::UsbHidGadgetConfig gadget_for(const config::Config& cfg) {
  const auto s = settings_of(cfg);
  kernel_test::UsbHidGadgetConfig g;
  g.report_descriptor = report_profile_descriptor(s->report);
  g.vendor_id = *s->select.vendor_id;
  g.product_id = *s->select.product_id;
  g.serial = kKernelSerial;
  g.product = "hapticd simulated HID device";
  return g;
}

// The gadget and the simulated device on its /dev/hidgN, for the report profile.
struct GadgetRig {
  explicit GadgetRig(const char* backend, std::vector<std::string> more = {})
      : sets(sets_for(backend, std::move(more))),
        cfg(load_example("hid-report.yaml", sets)),
        gadget(std::make_unique<kernel_test::UsbHidGadget>(gadget_for(cfg))),
        peer(std::make_unique<KernelPeer>(cfg, gadget->hidg_path())) {}
  sim::LoopbackPeer& device() { return *peer->peer; }
  std::vector<std::string> sets;
  config::Config cfg;
  std::unique_ptr<kernel_test::UsbHidGadget> gadget;
  std::unique_ptr<KernelPeer> peer;
};

class HidGadget : public ::testing::TestWithParam<const char*> {};

TEST_P(HidGadget, ReportProfileRendersTheSimDriversWall) {
  GadgetRig rig(GetParam());
  expect_the_sim_drivers_wall("hid-report.yaml", rig.sets, rig.device());
}

TEST_P(HidGadget, APeerThatStopsAnsweringFaultsWithZeroForce) {
  GadgetRig rig(GetParam());
  expect_fault_exit("hid-report.yaml", rig.sets, rig.device(), sim::PeerFault::kStopAnswering,
                    "stale encoder data");
}

TEST_P(HidGadget, AStatusFaultBitFaultsWithZeroForce) {
  GadgetRig rig(GetParam());
  expect_fault_exit("hid-report.yaml", rig.sets, rig.device(), sim::PeerFault::kDeviceFault,
                    "hid: the device reported a fault: status 0x1");
}

// A skip of 50 sequence numbers can meet an answer the emulator delivered late: 50 or 51.
TEST_P(HidGadget, SkippedSequenceNumbersFaultWithZeroForce) {
  GadgetRig rig(GetParam());
  expect_fault_exit("hid-report.yaml", rig.sets, rig.device(), sim::PeerFault::kSkipSequence,
                    "sequence skipped 5[0-9] samples");
}

TEST_P(HidGadget, AKilledHapticdLeavesNoForceBehind) {
  GadgetRig rig(GetParam());
  expect_no_force_after_sigkill("hid-report.yaml", rig.sets, rig.device());
}

// The device unplugged mid-run (the gadget unbound): a transport fault, zero, exit 1.
TEST_P(HidGadget, AnUnpluggedDeviceFaultsTheRun) {
  GadgetRig rig(GetParam(), {"safety.stale_fault_ticks=1000"});
  const Hapticd h = run_hapticd(
      with_sets({"run", "--config", example("hid-report.yaml"), "--duration", "30"},
                unchecked(rig.sets)),
      [&](pid_t) {
        ASSERT_TRUE(reference::wait_armed()) << "the direction check never armed the wall";
        ASSERT_TRUE(KernelPeer::wait_for([&] { return rig.device().applied_force() < -0.2; }));
        rig.peer.reset();
        rig.gadget.reset();
      });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_NE(faults(h).find("hid: the device is gone"), std::string::npos) << faults(h) << "\n"
                                                                          << h.log;
}

INSTANTIATE_TEST_SUITE_P(Backends, HidGadget, ::testing::Values("hidraw", "libusb"),
                         [](const auto& p) { return std::string(p.param); });

}  // namespace
}  // namespace hapticd::drivers::hid
