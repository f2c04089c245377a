// The pid profile with config/hid-openffboard.yaml against OpenFFBoard's own report descriptor
// (the reference device's, tests/reference/hid/openffboard_descriptor.h, written from the
// firmware): every report is found, and the bytes of the start-up are what the firmware's
// structures (Inc/ffb_defs.h: FFB_SetEffect_t, FFB_SetConstantForce_Data_t, FFB_EffOp_Data_t,
// the Device Control byte of one-bit flags) read as hapticd means them. Fast, in every run;
// the kernel test machine runs the whole device (tests/reference/hid).
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "fake_hid_device.h"
#include "hid_test_support.h"
#include "openffboard_descriptor.h"

namespace hapticd::drivers::hid {
namespace {

using Bytes = std::vector<std::uint8_t>;

TEST(OpenFfboardBytes, TheStartUpReadsAsTheFirmwaresStructuresMeanIt) {
  testing::FakeHidDevice fake(reference::openffboard_descriptor());
  // FFB_BlockLoad_Feature_Data_t: block 1, status 1 (success), 40 effects' RAM free.
  fake.on_get_feature = [](std::uint8_t id) {
    return id == 0x12 ? Bytes{0x12, 1, 1, 0x80, 0x0C} : Bytes{};
  };
  const auto s = testing::settings_of(
      testing::load_example("hid-openffboard.yaml", {"device.hid.liveness_ms=2000"}));
  HidDevice device(s, fake.opener(), 1e-3);
  device.configure();
  // The board reports its wheel at rest (gamepad report 1: buttons, then X) while the enable
  // waits for a report: it sends one only on change or every ~100 ms.
  std::thread board([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    Bytes gamepad(25, 0);
    gamepad[0] = 1;
    gamepad[9] = 0x10;  // X = 16 counts
    fake.send_input(gamepad);
  });
  device.enable();
  board.join();
  ASSERT_EQ(device.write(2.5), IoStatus::kOk);  // a quarter of the 10 N m full scale
  fake.wait_for(13);
  std::vector<Bytes> out = fake.outputs();
  Bytes create;
  for (const auto& m : fake.received()) {
    if (m.type == FrameType::kSetFeature) create = m.payload;
  }
  // Create New Effect: report 0x11, effectType 1 (the first of its list: constant force).
  ASSERT_GE(create.size(), 2u);
  EXPECT_EQ(create[0], 0x11);
  EXPECT_EQ(create[1], 1);
  // Device Control at configure: report 0x0C, byte 1 the flags: 4 stop all, then 2 disable.
  ASSERT_GE(out.size(), 8u);
  EXPECT_EQ(out[0], (Bytes{0x0C, 0x04}));
  EXPECT_EQ(out[1], (Bytes{0x0C, 0x02}));
  // FFB_SetEffect_t: block 1, type 1, duration 100 ms, gain 255, enableAxis X | direction
  // enable (bits 0 and 1 for one axis), directionX 27000: the firmware's torque is
  // -magnitude * sin(direction) (EffectsCalculator.cpp, calcComponentForce), +magnitude here,
  // which turns the wheel toward +X.
  const Bytes& effect = out[2];
  ASSERT_GE(effect.size(), 16u);
  EXPECT_EQ(effect[0], 0x01);
  EXPECT_EQ(effect[1], 1);
  EXPECT_EQ(effect[2], 1);
  EXPECT_EQ(effect[3] | effect[4] << 8, 100);
  EXPECT_EQ(effect[11], 255);
  EXPECT_EQ(effect[13] & 0x03, 0x03);
  // 27000 or 27001: the board declares Direction 0..36000, one more than a turn, and hapticd
  // rounds 270 / 360 of 36001 steps (hid-pidff takes 36000, 27000).
  const int direction = effect[14] | effect[15] << 8;
  EXPECT_NEAR(direction, 27000, 1);
  EXPECT_NEAR(-std::sin(2.0 * M_PI * direction / 36000.0), 1.0, 1e-6)
      << "the firmware's share of a positive magnitude along X (HidFFB: phaseX)";
  // FFB_SetConstantForce_Data_t: block 1, magnitude 0, then 2.5 / 10 * 32767.
  EXPECT_EQ(out[3], (Bytes{0x05, 1, 0, 0}));
  EXPECT_EQ(out[4], (Bytes{0x0D, 255})) << "Device Gain";
  EXPECT_EQ(out[5], (Bytes{0x0A, 1, 1, 1})) << "FFB_EffOp_Data_t: block 1, start, loop count 1";
  EXPECT_EQ(out[6], (Bytes{0x0C, 0x01})) << "Device Control: enable actuators";
  const Bytes& force = out.back();
  EXPECT_EQ(force[0], 0x05);
  EXPECT_EQ(static_cast<std::int16_t>(force[2] | force[3] << 8), 8192);
  PositionSample p;
  ASSERT_EQ(device.read(p), IoStatus::kOk);
  EXPECT_NEAR(p.position, 16.0 / 32767.0 * 7.853982, 1e-6) << "X of +-32767 over +-450 degrees";
  device.disable();
  fake.wait_for(fake.received().size() + 4);
  EXPECT_EQ(fake.outputs().back(), (Bytes{0x0B, 1})) << "Block Free of block 1, last";
}

}  // namespace
}  // namespace hapticd::drivers::hid
