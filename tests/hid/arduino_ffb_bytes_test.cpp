// The pid profile with config/hid-arduino-ffb.yaml against ArduinoJoystickWithFFBLibrary's own
// report descriptor (the reference device's, tests/reference/hid/arduino_ffb_descriptor.h,
// written from the library v1.0.0): Device Control found as hid-pidff finds it (the 0x96
// collection, no 0x95 around it), ids shared between a feature and an output report, and the
// bytes of the start-up as the library's structures (src/DynamicHID/PIDReportType.h) read
// them. Block Load is answered as DynamicHID_::GetReport does: once, then with report id 0.
// Fast, in every run; the kernel test machine runs the whole board (tests/reference/hid).
#include <gtest/gtest.h>

#include <cmath>

#include "arduino_ffb_descriptor.h"
#include "fake_hid_device.h"
#include "hid_test_support.h"

namespace hapticd::drivers::hid {
namespace {

using Bytes = std::vector<std::uint8_t>;
namespace ids = reference::arduino_ffb;

// USB_FFBReport_PIDBlockLoad_Feature_Data_t: block 1, loadStatus 1 (success), RAM available;
// its reportId is set to 0 once sent, so any later GET_REPORT reads id 0.
struct BlockLoadOnce {
  Bytes operator()(std::uint8_t id) {
    if (id != ids::kBlockLoad) return {};
    Bytes r{ids::kBlockLoad, 1, 1, 0x40, 0x06};
    if (answered++ > 0) r[0] = 0;
    return r;
  }
  int answered = 0;
};

TEST(ArduinoFfbBytes, TheStartUpReadsAsTheLibrarysStructuresMeanIt) {
  testing::FakeHidDevice fake(reference::arduino_ffb_descriptor());
  fake.on_get_feature = BlockLoadOnce{};
  const auto s = testing::settings_of(testing::load_example("hid-arduino-ffb.yaml"));
  HidDevice device(s, fake.opener(), 1e-3);
  device.configure();
  device.enable();
  ASSERT_EQ(device.write(0.25), IoStatus::kOk);  // a quarter of the 1 N m full scale
  fake.wait_for(13);
  std::vector<Bytes> out = fake.outputs();
  Bytes create;
  for (const auto& m : fake.received()) {
    if (m.type == FrameType::kSetFeature) create = m.payload;
  }
  // USB_FFBReport_CreateNewEffect_Feature_Data_t: feature report 5 (the id Set Constant Force
  // has as an output report), effectType 1: constant force, the first of its list.
  ASSERT_GE(create.size(), 2u);
  EXPECT_EQ(create[0], ids::kCreateNewEffect);
  EXPECT_EQ(create[1], 1);
  // USB_FFBReport_DeviceControl_Output_Data_t: report 12, control 3 (stop all), 2 (disable).
  ASSERT_GE(out.size(), 8u);
  EXPECT_EQ(out[0], (Bytes{ids::kDeviceControl, 3}));
  EXPECT_EQ(out[1], (Bytes{ids::kDeviceControl, 2}));
  // USB_FFBReport_SetEffect_Output_Data_t: block 1, type 1, duration 100 ms, gain 255,
  // triggerButton none, enableAxis X and DirectionEnable (bits 0 and 2), directionX 64 of the
  // 0..255 that Joystick.cpp reads as 0..360 degrees: sin(90.4 degrees), +1 along X.
  const Bytes& effect = out[2];
  ASSERT_GE(effect.size(), 13u);
  EXPECT_EQ(effect[0], ids::kSetEffect);
  EXPECT_EQ(effect[1], 1);
  EXPECT_EQ(effect[2], 1);
  EXPECT_EQ(effect[3] | effect[4] << 8, 100);
  EXPECT_EQ(effect[9], 255);
  EXPECT_EQ(effect[11] & 0x05, 0x05);
  EXPECT_EQ(effect[12], 64);
  EXPECT_NEAR(std::sin(effect[12] * 360.0 / 255.0 * M_PI / 180.0), 1.0, 1e-4)
      << "getEffectForce's angle_ratio for X";
  // USB_FFBReport_SetConstantForce_Output_Data_t: block 1, magnitude 0, then 0.25 of 10000.
  EXPECT_EQ(out[3], (Bytes{ids::kSetConstant, 1, 0, 0}));
  EXPECT_EQ(out[4], (Bytes{ids::kDeviceGain, 255})) << "Device Gain";
  EXPECT_EQ(out[5], (Bytes{ids::kEffectOperation, 1, 1, 1}))
      << "USB_FFBReport_EffectOperation_Output_Data_t: block 1, operation 1 (start), loop 1";
  EXPECT_EQ(out[6], (Bytes{ids::kDeviceControl, 1})) << "control 1: enable actuators";
  const Bytes& force = out.back();
  EXPECT_EQ(force[0], ids::kSetConstant);
  EXPECT_EQ(static_cast<std::int16_t>(force[2] | force[3] << 8), 2500);
  // The joystick's report 1: 8 buttons, then X, Y, Rx, Ry; no PID State ever.
  fake.send_input(Bytes{ids::kJoystickInput, 0, 0x10, 0x00, 0, 0, 0, 0, 0, 0});
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  PositionSample p;
  ASSERT_EQ(device.read(p), IoStatus::kOk);
  EXPECT_NEAR(p.position, 16.0 / 32767.0 * 3.141593, 1e-6);
  EXPECT_EQ(p.status, 0u) << "no PID State: nothing to fault on";
  device.disable();
  fake.wait_for(fake.received().size() + 4);
  EXPECT_EQ(fake.outputs().back(), (Bytes{ids::kBlockFree, 1})) << "Block Free of block 1, last";
}

}  // namespace
}  // namespace hapticd::drivers::hid
