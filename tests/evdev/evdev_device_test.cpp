// The evdev driver's Device against a scripted transport: what it asks of the kernel over the
// lifecycle, and how it reads what the kernel hands over - a tick without an axis event, a
// silent axis under force, events lost (SYN_DROPPED), the device stopping the effect itself,
// an unplugged device, a grab held elsewhere, the kernel's fuzz.
#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "device_counter.h"
#include "device_rig.h"
#include "drivers/evdev/evdev_device.h"
#include "fake_transport.h"

namespace hapticd::drivers::evdev {
namespace {

using hapticd::testing::counter_value;

using testing::Rig;

TEST(EvdevDevice, TheLifecycleUploadsPlaysUpdatesStopsAndErases) {
  Rig r;
  r.device->configure();
  EXPECT_EQ(r.script->uploads, 1) << "uploaded at configure";
  EXPECT_FALSE(r.script->grabbed);
  r.device->enable();
  EXPECT_TRUE(r.script->grabbed) << "grabbed while output is on";
  const auto& w = r.script->ff_writes;
  EXPECT_NE(std::find(w.begin(), w.end(), std::pair{kFfAutocenter, 0}), w.end())
      << "autocenter off while hapticd renders";
  EXPECT_EQ(w.back(), (std::pair{3, 1})) << "the effect played last";
  ASSERT_EQ(r.device->write(5.0), IoStatus::kOk);
  r.device->wait_output();  // the update thread made it
  EXPECT_EQ(r.script->levels.back(), 16384) << "half of full scale";
  for (const int d : r.script->directions) {
    EXPECT_EQ(d, 0xC000) << "the default direction, \"right\" (<linux/input.h>): toward +x";
  }
  r.device->disable();
  EXPECT_EQ(r.script->levels.back(), 0);
  EXPECT_NE(std::find(w.begin(), w.end(), std::pair{3, 0}), w.end()) << "stopped";
  EXPECT_EQ(r.script->erases, 1) << "erased at disable";
  EXPECT_EQ(w.back(), (std::pair{kFfAutocenter, 32768})) << "autocenter given back";
  EXPECT_FALSE(r.script->grabbed);
  r.device->enable();
  EXPECT_EQ(r.script->uploads, 2) << "uploaded again for the next enable";
}

TEST(EvdevDevice, ATickWithoutAnAxisEventHoldsThePositionTheKernelHas) {
  Rig r;
  r.device->configure();
  r.device->enable();
  PositionSample s;
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_TRUE(s.flags & kSampleHeld);
  EXPECT_DOUBLE_EQ(s.position, -0.01) << "the kernel's value at enable";
  r.frame(500, 12345);
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_FALSE(s.flags & kSampleHeld);
  EXPECT_DOUBLE_EQ(s.position, 0.025);
  EXPECT_EQ(s.time_ns, 12345) << "the event's kernel time";
}

TEST(EvdevDevice, ASilentAxisUnderForceIsStaleOnlyPastTheLivenessBound) {
  Rig r(20.0);
  r.device->configure();
  r.device->enable();
  PositionSample s;
  ASSERT_EQ(r.device->write(0.0), IoStatus::kOk);
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  EXPECT_EQ(r.device->read(s), IoStatus::kOk) << "no force: a still axis is fine";
  ASSERT_EQ(r.device->write(0.0), IoStatus::kOk);  // the tick before the push
  ASSERT_EQ(r.device->write(2.0), IoStatus::kOk);
  EXPECT_EQ(r.device->read(s), IoStatus::kOk);
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  EXPECT_EQ(r.device->read(s), IoStatus::kNoNewData) << "pushed and silent past the bound";
  r.frame(10);
  EXPECT_EQ(r.device->read(s), IoStatus::kOk) << "an event ends the silence";
}

TEST(EvdevDevice, EventsLostAreCountedAndTheResyncedStateIsUsed) {
  Rig r;
  r.device->configure();
  r.device->enable();
  r.script->events.push_back({ReadStatus::kEvent, {kEvAbs, 0, 100, 1}});  // no SYN: cut off
  r.script->events.push_back({ReadStatus::kDropped, {kEvSyn, kSynDropped, 0, 2}});
  r.frame(700, 3);
  PositionSample s;
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(s.position, 0.035);
  EXPECT_EQ(counter_value(*r.device, "syn_dropped"), 1u);
}

// libevdev hands an event over only after taking it into its own state, and its resync after
// SYN_DROPPED repeats only what differs from that state: an axis value cut off by the drop,
// and still the kernel's, is never sent again. A device then held still must read there.
TEST(EvdevDevice, AnAxisValueCutOffBySynDroppedIsThePositionAfterTheResync) {
  Rig r;
  r.device->configure();
  r.device->enable();
  r.script->events.push_back({ReadStatus::kEvent, {kEvAbs, 0, 100, 1}});  // no SYN: cut off
  r.script->events.push_back({ReadStatus::kDropped, {kEvSyn, kSynDropped, 0, 2}});
  // The resync finds the kernel's value equal to libevdev's (100): it says nothing.
  PositionSample s;
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position, 0.005, 1e-12) << "the kernel's value, not the one before the drop";
  EXPECT_FALSE(s.flags & kSampleHeld) << "a new position: the loop takes only a new one";
  EXPECT_EQ(s.time_ns, 2);
  ASSERT_EQ(r.device->read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position, 0.005, 1e-12) << "and it holds there";
}

TEST(EvdevDevice, TheDeviceStoppingTheEffectIsADeviceFaultWithZeroForce) {
  Rig r;
  r.device->configure();
  r.device->enable();
  ASSERT_EQ(r.device->write(3.0), IoStatus::kOk);
  r.script->events.push_back({ReadStatus::kEvent, {kEvFfStatus, 3, kFfStatusStopped, 1}});
  PositionSample s;
  EXPECT_EQ(r.device->read(s), IoStatus::kDeviceFault);
  r.device->wait_output();  // the update thread stops it, then makes level 0
  const std::vector<std::string> tail(r.script->calls.end() - 2, r.script->calls.end());
  EXPECT_EQ(tail, (std::vector<std::string>{"write 3 0", "update 0"}));
  EXPECT_NE(r.device->describe_fault().find("stopped hapticd's force-feedback effect"),
            std::string::npos);
}

TEST(EvdevDevice, AnUnpluggedDeviceIsATransportFaultSaidSo) {
  Rig r;
  r.device->configure();
  r.device->enable();
  r.script->read_error = ENODEV;
  PositionSample s;
  EXPECT_EQ(r.device->read(s), IoStatus::kTransportFault);
  EXPECT_NE(r.device->describe_fault().find("the device is gone"), std::string::npos)
      << r.device->describe_fault();
}

// effect_updates is what the device was told: a level the kernel refused is not one of them.
// The update is made on the update thread, so the refusal is the next write's transport fault.
TEST(EvdevDevice, AnUpdateTheKernelRefusesIsATransportFaultAtTheNextWriteAndNoUpdate) {
  Rig r;
  r.device->configure();
  r.device->enable();
  ASSERT_EQ(r.device->write(1.0), IoStatus::kOk);
  r.device->wait_output();
  const std::uint64_t taken = counter_value(*r.device, "effect_updates");
  EXPECT_GT(taken, 0u);
  r.script->update_error = EIO;
  ASSERT_EQ(r.device->write(2.0), IoStatus::kOk) << "handed on, not waited for";
  r.device->wait_output();
  EXPECT_EQ(r.device->write(3.0), IoStatus::kTransportFault);
  EXPECT_EQ(counter_value(*r.device, "effect_updates"), taken) << "the refused level counted";
  EXPECT_NE(r.device->describe_fault().find("Input/output error"), std::string::npos)
      << r.device->describe_fault();
}

TEST(EvdevDevice, AGrabHeldElsewhereRefusesTheEnableAndLeavesNothingPlaying) {
  Rig r;
  r.device->configure();
  r.script->grabbed_elsewhere = true;
  EXPECT_THROW(r.device->enable(), DeviceError);
  EXPECT_EQ(r.device->state(), DeviceState::kConfigured);
  for (const auto& [code, value] : r.script->ff_writes) {
    EXPECT_FALSE(code == 3 && value == 1) << "the effect never played";
  }
}

TEST(EvdevDevice, TheKernelsFuzzIsOffWhileHapticdHasTheDeviceAndGivenBack) {
  Rig r;
  r.script->facts.fuzz = 16;
  r.device->configure();
  EXPECT_EQ(r.script->fuzz_set, 0);
  ASSERT_EQ(r.device->notices().size(), 1u);
  EXPECT_NE(r.device->notices()[0].find("fuzz 16"), std::string::npos);
  r.device->close();
  EXPECT_EQ(r.script->fuzz_set, 16);
}

TEST(EvdevDevice, AKernelDriverOfAnotherClassIsANotice) {
  InputListing l;
  l.path = "/dev/input/event7";
  l.kernel_driver = "logitech";  // ff-memless, while the settings say pidff
  Rig r(0.0, l);
  r.device->configure();
  ASSERT_EQ(r.device->notices().size(), 1u);
  EXPECT_NE(r.device->notices()[0].find("memless"), std::string::npos) << r.device->notices()[0];
}

TEST(EvdevDevice, ADeviceWithoutTheAxisOrConstantForceIsRefusedNamingIt) {
  Rig a;
  a.script->facts.has_axis = false;
  EXPECT_THROW(
      {
        try {
          a.device->configure();
        } catch (const DeviceError& e) {
          EXPECT_NE(std::string(e.what()).find("has no ABS_X axis"), std::string::npos);
          throw;
        }
      },
      DeviceError);
  Rig b;
  b.script->facts.ff_constant = false;
  EXPECT_THROW(b.device->configure(), DeviceError);
}

}  // namespace
}  // namespace hapticd::drivers::evdev
