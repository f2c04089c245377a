// The Falcon's Device (docs/drivers/falcon.md) against the simulated bootloader and firmware of
// fake_falcon_link.h, in the test's thread: the load, homing before any position is read, what
// a tick reads and sends, and each way it faults.
#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <fstream>
#include <thread>

#include "drivers/falcon/falcon_device.h"
#include "fake_falcon_link.h"
#include "falcon_image.h"

namespace hapticd::drivers::falcon::testing {
namespace {

struct Rig {
  explicit Rig(double liveness_ms = 100.0, double homing_timeout_s = 1.0) {
    settings = std::make_shared<FalconSettings>();
    settings->firmware = hapticd::testing::falcon_test_image();
    settings->liveness_ms = liveness_ms;
    settings->homing_timeout_s = homing_timeout_s;
    device = std::make_unique<FalconDevice>(
        settings,
        [this]() -> std::unique_ptr<FalconTransport> {
          auto l = std::make_unique<FakeFalconLink>();
          link = l.get();
          setup(*l);
          return l;
        },
        0.001, kFast);
  }
  std::function<void(FakeFalconLink&)> setup = [](FakeFalconLink&) {};
  std::shared_ptr<FalconSettings> settings;
  FakeFalconLink* link = nullptr;
  std::unique_ptr<FalconDevice> device;
  std::array<PositionSample, 3> s{};
  IoStatus read() { return device->read(std::span<PositionSample>(s)); }
};

TEST(FalconDevice, ConfigureLoadsThenHomesWithTheLedRedAndDeclaresThreeJointsAndOneSample) {
  Rig rig;
  rig.setup = [](FakeFalconLink& l) {
    l.ignore_first_pulses = 1;
    l.homing_packets = 5;
  };
  rig.device->configure();
  EXPECT_EQ(rig.link->pulses, 2);
  EXPECT_EQ(rig.device->info().joints, 3u);
  EXPECT_EQ(rig.device->info().transport_delay_samples, 1);
  EXPECT_TRUE(rig.link->last_homing);
  EXPECT_EQ(rig.link->last_leds, kLedRed) << "homing is the last thing configure did";
  ASSERT_EQ(rig.device->notices().size(), 1u);
  EXPECT_NE(rig.device->notices()[0].find("try 2: loaded"), std::string::npos);
}

TEST(FalconDevice, AFirmwareAlreadyRunningIsNotLoadedAgain) {
  Rig rig;
  rig.setup = [](FakeFalconLink& l) {
    l.firmware_running = true;
    l.divisor = 2;
  };
  rig.device->configure();
  EXPECT_EQ(rig.link->pulses, 0) << "no reset: the running firmware is kept";
  EXPECT_NE(rig.device->notices().at(0).find("running already"), std::string::npos);
}

TEST(FalconDevice, AGripNeverHomedRefusesConfigureSayingWhatToDo) {
  Rig rig(100.0, 1.0);
  rig.setup = [](FakeFalconLink& l) { l.homing_packets = 1 << 30; };
  try {
    rig.device->configure();
    FAIL() << "configured without homing";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("not homed within 1 s (encoders not homed: 0, 1, 2)"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("pull the grip all the way out"), std::string::npos);
  }
  EXPECT_EQ(rig.device->state(), DeviceState::kUnconfigured);
}

TEST(FalconDevice, ATickReadsEachArmsAngleAndSendsEachTorqueInCountsWithTheHomingBit) {
  Rig rig;
  rig.device->configure();
  rig.link->encoders = {0, 1000, -2000};
  rig.read();  // sends the zero packet the firmware answers
  ASSERT_EQ(rig.read(), IoStatus::kOk);
  for (int j = 0; j < 3; ++j) {
    EXPECT_DOUBLE_EQ(rig.s[j].position, arm_angle(rig.link->encoders[j])) << j;
    EXPECT_EQ(rig.s[j].status, 0x70u) << "homed bits in the status";
  }
  EXPECT_EQ(rig.link->last_leds, kLedBlue) << "homed, output off";
  rig.device->enable();
  EXPECT_EQ(rig.link->last_leds, kLedGreen);
  const std::array<double, 3> torque = {0.1, -0.2, 0.05};
  ASSERT_EQ(rig.device->write(torque), IoStatus::kOk);
  EXPECT_EQ(rig.link->last_motor, (std::array<std::int16_t, 3>{-1000, 2000, -500}))
      << "-10000 counts per N m: libnifalcon's scale";
  EXPECT_TRUE(rig.link->last_homing) << "every packet keeps the device homed";
  rig.device->disable();
  EXPECT_EQ(rig.link->last_motor, (std::array<std::int16_t, 3>{0, 0, 0}));
  EXPECT_EQ(rig.link->last_leds, kLedBlue);
}

TEST(FalconDevice, AMalformedPacketIsCountedNotRead) {
  Rig rig;
  rig.device->configure();
  rig.read();
  rig.link->corrupt_next = true;
  rig.read();  // this read's zero packet is answered corrupt
  rig.link->encoders = {5, 5, 5};
  EXPECT_EQ(rig.read(), IoStatus::kNoNewData) << "the corrupt answer is no sample";
  EXPECT_EQ(rig.read(), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(rig.s[0].position, arm_angle(5));
  for (const base::Counter& c : rig.device->counters()) {
    if (c.name() == "malformed") {
      EXPECT_EQ(c.value(), 1u);
    }
  }
}

TEST(FalconDevice, ASilentFirmwareIsATransportFaultAfterLiveness) {
  Rig rig(20.0);
  rig.device->configure();
  rig.link->silent_firmware = true;
  IoStatus r = IoStatus::kOk;
  for (int i = 0; i < 200 && r != IoStatus::kTransportFault; ++i) {
    r = rig.read();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(r, IoStatus::kTransportFault);
  EXPECT_NE(rig.device->describe_fault().find("no packet for 20 ms"), std::string::npos)
      << rig.device->describe_fault();
}

// The firmware speaks only when spoken to: the gate's time between configure and the first
// tick is no silence.
TEST(FalconDevice, APauseBeforeTheFirstTickIsNoSilence) {
  Rig rig(20.0);
  rig.device->configure();
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  EXPECT_NE(rig.read(), IoStatus::kTransportFault) << rig.device->describe_fault();
  EXPECT_EQ(rig.read(), IoStatus::kOk);
}

TEST(FalconDevice, LostHomingIsADeviceFaultAndUnplugATransportFaultEachWithZeroForce) {
  Rig rig;
  rig.device->configure();
  rig.device->enable();
  rig.link->lose_homing = true;
  const std::array<double, 3> torque = {0.1, 0.1, 0.1};
  rig.device->write(torque);
  EXPECT_EQ(rig.read(), IoStatus::kDeviceFault);
  EXPECT_NE(rig.device->describe_fault().find("lost its homing"), std::string::npos);
  EXPECT_EQ(rig.link->last_motor, (std::array<std::int16_t, 3>{0, 0, 0}));
  EXPECT_EQ(rig.link->last_leds, kLedRed);

  Rig unplug;
  unplug.device->configure();
  unplug.device->enable();
  unplug.link->unplugged = true;
  EXPECT_EQ(unplug.read(), IoStatus::kTransportFault);
  EXPECT_EQ(unplug.device->describe_fault(), "falcon: the device is gone");
}

}  // namespace
}  // namespace hapticd::drivers::falcon::testing
