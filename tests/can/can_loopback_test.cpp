// Each profile's device against its simulated drive over a socketpair: start-up checked step
// by step (with the errors a person must be able to act on), every fault named with its code,
// malformed frames counted and named, never a crash; clear_fault and the emergency stop.
#include <gtest/gtest.h>

#include "can_rig.h"
#include "drivers/can/odrive_protocol.h"
#include "sim/peers/can/cia402_peer.h"
#include "sim/peers/can/odrive_peer.h"

namespace hapticd::drivers::can::testing {
namespace {

const char* kCia = "can-cia402.yaml";
const char* kOdrive = "can-odrive.yaml";

std::string configure_error(CanRig& rig) {
  try {
    rig.device().configure();
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

TEST(CanCia402, ConfigureReadsRatedTorqueAndDeclaresOneSample) {
  CanRig rig(load_example(kCia));
  rig.device().configure();
  EXPECT_EQ(rig.device().info().transport_delay_samples, 1);
  EXPECT_NE(rig.device().info().description.find("rated torque 500 mN m"), std::string::npos)
      << rig.device().info().description;
  EXPECT_FALSE(rig.peer().output_on()) << "configure leaves the power stage off";
  rig.device().enable();
  EXPECT_EQ(dynamic_cast<sim::Cia402Peer&>(rig.peer()).power_state(),
            cia402::PowerState::kOperationEnabled);
  PositionSample s;
  EXPECT_EQ(rig.tick(2.5, s), IoStatus::kNoNewData) << "no SYNC has been sent before the first";
  EXPECT_EQ(rig.tick(2.5, s), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(rig.peer().applied_force(), 2.5) << "50 per mille of 0.5 N m through 10 mm";
  EXPECT_NEAR(s.position, -0.02, 1e-5);
  EXPECT_EQ(s.status & 0x6F, 0x27) << "statusword: operation enabled";
  EXPECT_TRUE(s.flags & kSampleHasTime);
  rig.device().disable();
  rig.settle();
  EXPECT_EQ(dynamic_cast<sim::Cia402Peer&>(rig.peer()).power_state(),
            cia402::PowerState::kReadyToSwitchOn)
      << "disable: controlword 0x06";
}

TEST(CanCia402, VerifyingTheMappingOfAFactoryFreshDriveNamesTheObject) {
  CanRig rig(load_example(kCia, {"device.can.cia402.pdo_mapping=verify"}));
  const std::string e = configure_error(rig);
  EXPECT_NE(e.find("SDO 0x1400:02 (PDO mapping): is 0x000000FF, hapticd needs 0x00000001"),
            std::string::npos)
      << e;
  EXPECT_EQ(rig.device().state(), DeviceState::kUnconfigured);
}

TEST(CanCia402, AnUnansweredSdoNamesTheObjectAndTheTimeOut) {
  CanRig rig(load_example(kCia, {"device.can.sdo_timeout_ms=100"}));
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kStopSdo));
  const std::string e = configure_error(rig);
  EXPECT_NE(e.find("SDO 0x1000:00 (device type): no answer within 100 ms"), std::string::npos) << e;
}

TEST(CanCia402, AnAbortedSdoCarriesCiA301sText) {
  CanRig rig(load_example(kCia));
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kAbortSdo));
  const std::string e = configure_error(rig);
  EXPECT_NE(e.find("SDO 0x1000:00 (device type): aborted with 0x08000022 data cannot be "
                   "transferred or stored in the present device state"),
            std::string::npos)
      << e;
  EXPECT_EQ(counter(rig.device(), "sdo_aborts").value(), 1u);
}

TEST(CanCia402, ANodeIdWithoutADriveIsNamedByItsTimeOut) {
  CanRig rig(load_example(kCia, {"device.can.node_id=2", "device.can.sdo_timeout_ms=100"}),
             load_example(kCia));
  const std::string e = configure_error(rig);
  EXPECT_NE(e.find("node 2"), std::string::npos) << e;
  EXPECT_NE(e.find("no answer within 100 ms"), std::string::npos) << e;
}

TEST(CanCia402, EmcyIsADeviceFaultNamedWithItsCode) {
  CanRig rig(load_example(kCia));
  rig.device().configure();
  rig.device().enable();
  EXPECT_EQ(rig.run_until_fault(3.0, 5), IoStatus::kOk);
  ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kDeviceFault));
  EXPECT_EQ(rig.run_until_fault(3.0, 5), IoStatus::kDeviceFault);
  EXPECT_EQ(rig.device().fault().code, 0x032310u) << "error register << 16 | EMCY code";
  EXPECT_EQ(rig.device().describe_fault(),
            "can: cia402 node 1 sent EMCY 0x2310 continuous over-current (device output side) "
            "(error register 0x03)");
  EXPECT_EQ(rig.peer().applied_force(), 0.0);
  // clear_fault resets the drive's fault and the state machine is walked again.
  rig.device().clear_fault();
  EXPECT_EQ(rig.device().state(), DeviceState::kConfigured);
  rig.device().enable();
  EXPECT_EQ(rig.run_until_fault(1.5, 3), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(rig.peer().applied_force(), 1.5);
}

TEST(CanCia402, TruncatedEmcyWrongLengthUnknownIdsAndJunkAreCountedAndNamed) {
  CanRig rig(load_example(kCia));
  rig.device().configure();
  rig.device().enable();
  PositionSample s;
  rig.tick(0.0, s);
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kWrongLengthPdo));
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kUnknownIds));
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kMalformedMessage));
  rig.tick(0.0, s);  // SYNC: the drive answers with a 5-byte TPDO1 and an unknown id
  EXPECT_EQ(rig.tick(0.0, s), IoStatus::kNoNewData) << "a TPDO of the wrong length is no sample";
  EXPECT_EQ(rig.tick(0.0, s), IoStatus::kOk);
  for (const char* name : {"wrong_length", "unknown_ids", "malformed_messages"}) {
    EXPECT_EQ(counter(rig.device(), name).kind(), base::CounterKind::kAnomaly) << name;
  }
  EXPECT_EQ(counter(rig.device(), "wrong_length").value(), 1u);
  EXPECT_GE(counter(rig.device(), "unknown_ids").value(), 1u);
  EXPECT_EQ(counter(rig.device(), "malformed_messages").value(), 1u);
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kTruncatedEmcy));
  EXPECT_EQ(rig.run_until_fault(0.0, 3), IoStatus::kDeviceFault);
  const std::string why = rig.device().describe_fault();
  EXPECT_NE(why.find("EMCY frame truncated to 2 bytes"), std::string::npos) << why;
  EXPECT_NE(why.find("also seen on the bus: 1 malformed messages"), std::string::npos) << why;
  EXPECT_NE(why.find("1 frames of the wrong length"), std::string::npos) << why;
}

TEST(CanCia402, LostHeartbeatAndStalePdosAndBusOff) {
  {
    CanRig rig(load_example(kCia));
    rig.device().configure();
    rig.device().enable();
    ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kStopHeartbeat));
    // 300 ms at 1 kHz: the 301st tick without one faults.
    EXPECT_EQ(rig.run_until_fault(1.0, 400), IoStatus::kDeviceFault);
    EXPECT_NE(rig.device().describe_fault().find("no heartbeat (0x701) for 301 ticks"),
              std::string::npos)
        << rig.device().describe_fault();
  }
  {
    CanRig rig(load_example(kCia));
    rig.device().configure();
    rig.device().enable();
    PositionSample s;
    rig.tick(1.0, s);
    ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kStopAnswering));
    EXPECT_EQ(rig.tick(1.0, s), IoStatus::kOk) << "the TPDO of the SYNC before";
    EXPECT_EQ(rig.tick(1.0, s), IoStatus::kNoNewData) << "a dropped PDO is stale data";
  }
  {
    CanRig rig(load_example(kCia));
    rig.device().configure();
    rig.device().enable();
    rig.run_until_fault(2.0, 3);
    ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kTransportFault));
    EXPECT_EQ(rig.run_until_fault(2.0, 3), IoStatus::kTransportFault);
    EXPECT_NE(rig.device().describe_fault().find("went bus-off"), std::string::npos);
    EXPECT_EQ(rig.peer().applied_force(), 0.0) << "0x6007 disable voltage on losing the bus";
  }
}

TEST(CanCia402, EmergencyStopWritesZeroTorqueAndShutdown) {
  CanRig rig(load_example(kCia));
  rig.device().configure();
  rig.device().enable();
  rig.run_until_fault(4.0, 3);
  ASSERT_EQ(rig.peer().applied_force(), 4.0);
  rig.device().emergency_stop();
  rig.settle();
  EXPECT_EQ(rig.peer().applied_force(), 0.0);
  EXPECT_FALSE(rig.peer().output_on());
}

TEST(CanOdrive, DetectsFirmwareAndEnablesClosedLoop) {
  CanRig rig(load_example(kOdrive));
  rig.device().configure();
  EXPECT_NE(rig.device().info().description.find("firmware 0.6.10, hardware 4.4.58"),
            std::string::npos)
      << rig.device().info().description;
  rig.device().enable();
  EXPECT_EQ(dynamic_cast<sim::OdrivePeer&>(rig.peer()).axis_state(), odrive::kAxisClosedLoop);
  EXPECT_EQ(rig.run_until_fault(3.0, 3), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(rig.peer().applied_force(), 3.0);
  rig.device().disable();
  rig.settle();
  EXPECT_EQ(dynamic_cast<sim::OdrivePeer&>(rig.peer()).axis_state(), odrive::kAxisIdle);
}

TEST(CanOdrive, Firmware05IsDetectedBySilenceAndItsAxisErrorsNamed) {
  // The simulated axis runs 0.5 when the configuration says so; the driver, told to detect,
  // hears no answer to Get_Version and speaks 0.5.
  CanRig rig(load_example(kOdrive, {"device.can.odrive.firmware=auto"}),
             load_example(kOdrive, {"device.can.odrive.firmware=0.5"}));
  rig.device().configure();
  EXPECT_NE(rig.device().info().description.find("firmware 0.5 (no answer to Get_Version)"),
            std::string::npos)
      << rig.device().info().description;
  rig.device().enable();
  rig.run_until_fault(1.0, 3);
  ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kDeviceFault));
  EXPECT_EQ(rig.run_until_fault(1.0, 3), IoStatus::kDeviceFault);
  EXPECT_EQ(rig.device().fault().code, 0x40u);
  EXPECT_NE(rig.device().describe_fault().find("axis error 0x00000040 MOTOR_FAILED (firmware 0.5)"),
            std::string::npos)
      << rig.device().describe_fault();
}

TEST(CanOdrive, AxisErrorOn06AndClearErrors) {
  CanRig rig(load_example(kOdrive));
  rig.device().configure();
  rig.device().enable();
  ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kDeviceFault));
  EXPECT_EQ(rig.run_until_fault(1.0, 3), IoStatus::kDeviceFault);
  EXPECT_NE(rig.device().describe_fault().find("CURRENT_LIMIT_VIOLATION"), std::string::npos);
  rig.device().clear_fault();
  rig.device().enable();
  EXPECT_EQ(rig.run_until_fault(1.0, 3), IoStatus::kOk);
}

TEST(CanOdrive, WatchdogEndpointsAreWrittenAndReadBackOn06) {
  CanRig rig(load_example(kOdrive, {"device.can.odrive.watchdog_timeout_endpoint=301",
                                    "device.can.odrive.enable_watchdog_endpoint=300"}));
  EXPECT_NO_THROW(rig.device().configure());
}

TEST(CanOdrive, CyclicEstimatesDeclareTheirPeriod) {
  const config::Config cfg = load_example(kOdrive, {"device.can.odrive.position_source=cyclic",
                                                    "device.can.odrive.cyclic_period_ms=2"});
  EXPECT_EQ(wiring::find_driver("can").declared_delay(cfg), 2);
  CanRig rig(cfg);
  rig.device().configure();
  EXPECT_EQ(rig.device().info().transport_delay_samples, 2);
  rig.device().enable();
  PositionSample s;
  int fresh = 0;
  for (int i = 0; i < 10; ++i) fresh += rig.tick(0.5, s) == IoStatus::kOk ? 1 : 0;
  EXPECT_EQ(fresh, 4) << "one estimate every second torque command, the first after two";
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
