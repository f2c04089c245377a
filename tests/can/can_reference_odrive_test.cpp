// The ODrive profile against an axis as firmware 0.5.6 behaves (tests/reference/can/
// odrive_056.h): set up as docs/drivers/can.md asks (watchdog on), straight after power-on.
#include <gtest/gtest.h>

#include <cmath>

#include "reference/can/odrive_056.h"
#include "reference/can/odrive_06.h"
#include "reference_rig.h"

namespace hapticd::drivers::can::testing {
namespace {

using reference::Odrive056;

config::Config odrive_config(std::vector<std::string> sets = {}) {
  sets.push_back("device.can.odrive.watchdog_timeout_s=0.25");
  return load_example("can-odrive.yaml", sets, false);
}

reference::PlantParameters still_axis() {
  reference::PlantParameters p;
  p.damping = 10.0;
  return p;
}

// Issue 23, 1: every 0.5 axis with its watchdog on reports WATCHDOG_TIMER_EXPIRED until fed;
// the driver clears exactly that, and feeds the watchdog across the gate's time to enable.
TEST(CanReferenceOdrive, Firmware05WithTheWatchdogOnStartsStraightAfterPowerOn) {
  Odrive056 axis({}, still_axis(), reference::monotonic_ns());
  ReferenceRig rig(odrive_config(), axis);  // powered on, on the bus
  sleep_ms(300);  // nobody talked to it since power-on: the watchdog has expired
  ASSERT_EQ(axis.axis_error(), Odrive056::kWatchdogExpired);
  ASSERT_NO_THROW(rig.device->configure());
  EXPECT_EQ(axis.axis_error(), 0u) << "cleared at configure";
  sleep_ms(700);  // the gate's analysis between configure and enable
  EXPECT_EQ(axis.axis_error(), 0u) << "fed from configure to enable";
  ASSERT_NO_THROW(rig.device->enable());
  EXPECT_EQ(rig.run(0.5, 300), IoStatus::kOk) << rig.device->describe_fault();
  EXPECT_EQ(axis.state(), Odrive056::kClosedLoop);
  EXPECT_GT(axis.motor_force_n(), 0.0) << "the torque commanded reaches the axis";
  EXPECT_EQ(axis.unmodelled_mode_passes(), 0u) << "torque control was selected";
}

TEST(CanReferenceOdrive, AnyOtherAxisErrorIsStillRefused) {
  Odrive056 axis({}, still_axis(), reference::monotonic_ns());
  ReferenceRig rig(odrive_config({"device.can.odrive.firmware=0.5"}), axis);
  sleep_ms(300);
  axis.raise_axis_error(Odrive056::kMotorFailed);  // and the watchdog's
  try {
    rig.device->configure();
    FAIL() << "configured an axis with MOTOR_FAILED";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("MOTOR_FAILED"), std::string::npos) << e.what();
  }
  EXPECT_EQ(axis.axis_error() & Odrive056::kMotorFailed, Odrive056::kMotorFailed)
      << "not cleared: Clear_Errors would clear every error, so it is sent for the watchdog's only";
}

// While a fault is held (the service waits for clear-fault) the axis is idle and fed: its
// error stays the one that faulted the run, not one the watchdog added later.
TEST(CanReferenceOdrive, AHeldFaultKeepsTheWatchdogFed) {
  Odrive056 axis({}, still_axis(), reference::monotonic_ns());
  ReferenceRig rig(odrive_config({"device.can.odrive.firmware=0.5"}), axis);
  rig.device->configure();
  rig.device->enable();
  ASSERT_EQ(rig.run(0.0, 100), IoStatus::kOk);
  axis.raise_axis_error(Odrive056::kMotorFailed);
  EXPECT_EQ(rig.run(0.0, 500), IoStatus::kDeviceFault);
  rig.device->disable();
  sleep_ms(600);
  EXPECT_EQ(axis.axis_error(), Odrive056::kMotorFailed);
  EXPECT_EQ(axis.state(), Odrive056::kIdle);
}

// Issue 23, 2: at the firmware's defaults a hand that moves the axis faster than vel_limit x
// vel_limit_tolerance faults it with CONTROLLER_FAILED; the fault says why.
TEST(CanReferenceOdrive, TheOverspeedOfTheTorqueModeVelocityLimitIsNamed) {
  reference::PlantParameters fast;
  fast.hand_force = 5.0;    // 2.5 m/s if nothing held it: 25 turn/s
  fast.hand_start_s = 0.6;  // once enabled
  fast.hand_ramp_s = 0.05;
  Odrive056 axis({}, fast, reference::monotonic_ns());
  ReferenceRig rig(odrive_config({"device.can.odrive.firmware=0.5"}), axis);
  rig.device->configure();
  rig.device->enable();
  ASSERT_EQ(rig.run(0.0, 2000), IoStatus::kDeviceFault);
  rig.device->disable();  // reads controller.error back (0.5.6 answers Get_Controller_Error)
  EXPECT_EQ(axis.controller_error(), Odrive056::kOverspeed);
  const std::string why = rig.device->describe_fault();
  EXPECT_NE(why.find("CONTROLLER_FAILED"), std::string::npos) << why;
  EXPECT_NE(why.find("OVERSPEED"), std::string::npos) << why;
  EXPECT_NE(why.find("vel_limit"), std::string::npos) << why;
  EXPECT_NE(why.find("enable_overspeed_error"), std::string::npos) << why;
  EXPECT_GT(counter(*rig.device, "over_vel_limit").value(), 0u)
      << "the braking before the fault is counted";
  EXPECT_NE(why.find("also seen on the bus"), std::string::npos) << why;
  EXPECT_NE(why.find("ticks above the axis's torque-mode velocity limit"), std::string::npos)
      << why;
}

// 0.5 sends the estimates every 10 ms by default besides answering each request: the driver
// takes only the answer (samples one period apart), counts the others and says so.
TEST(CanReferenceOdrive, CyclicEstimatesAreNotTakenForAnswersAndAreNoticed) {
  Odrive056 axis({}, still_axis(), reference::monotonic_ns());
  ReferenceRig rig(odrive_config({"device.can.odrive.firmware=0.5"}), axis);
  rig.device->configure();
  const std::string notices = joined(rig.device->notices());
  EXPECT_NE(notices.find("encoder_rate_ms"), std::string::npos) << notices;
  rig.device->enable();
  ASSERT_EQ(rig.run(0.0, 500), IoStatus::kOk);
  EXPECT_GT(counter(*rig.device, "unsolicited_estimates").value(), 20u);
  // Each sample answered its own tick's request: none is older than the tick before it.
  for (std::size_t i = 1; i < rig.samples.size(); ++i) {
    EXPECT_GT(rig.samples[i].time_ns, rig.samples[i - 1].time_ns) << i;
  }
}

TEST(CanReferenceOdrive, CheckWarnsOfTheTorqueModeVelocityLimitInAxisUnits) {
  const auto notes = wiring::find_driver("can").notes(odrive_config());
  const std::string all = joined(notes);
  EXPECT_NE(all.find("controller.config.vel_limit = 2 turn/s (0.196 axis units/s"),
            std::string::npos)
      << all;
  EXPECT_EQ(
      joined(wiring::find_driver("can").notes(odrive_config({"device.can.odrive.vel_limit=0"})))
          .find("vel_limit"),
      std::string::npos);
}

// Issue 34, 3: an ODrive Pro / S1 (0.6) disarmed by a DC-bus dip shorter than its heartbeat
// period: by its next heartbeat it is IDLE with no active error. The fault is latched at once
// with zero torque, Get_Error is asked with it, and the disarm reason is named.
TEST(CanReferenceOdrive, Firmware06DisarmedByADcBusDipIsAskedWhy) {
  reference::Odrive06 axis({}, still_axis(), reference::monotonic_ns());
  ReferenceRig rig(odrive_config({"device.can.odrive.vel_limit=0"}), axis);  // firmware auto
  ASSERT_NO_THROW(rig.device->configure());
  EXPECT_NE(rig.device->info().description.find("firmware 0.6.10"), std::string::npos)
      << rig.device->info().description;
  ASSERT_NO_THROW(rig.device->enable());
  ASSERT_EQ(rig.run(0.5, 300), IoStatus::kOk) << rig.device->describe_fault();
  ASSERT_TRUE(axis.armed());
  axis.dip_dc_bus(20);
  ASSERT_EQ(rig.run(0.5, 1000), IoStatus::kDeviceFault);
  sleep_ms(50);
  EXPECT_FALSE(axis.armed());
  EXPECT_EQ(axis.active_errors(), 0u) << "the dip is over";
  EXPECT_EQ(axis.disarm_reason(), reference::Odrive06::kDcBusUnderVoltage);
  EXPECT_EQ(axis.motor_force_n(), 0.0);
  EXPECT_EQ(axis.error_requests(), 1) << "asked with the latch's zero torque, before disable";
  rig.device->disable();
  EXPECT_EQ(axis.error_requests(), 1) << "disable took that answer";
  const std::string why = rig.device->describe_fault();
  EXPECT_NE(why.find("left CLOSED_LOOP_CONTROL by itself: its heartbeat says IDLE; disarm reason "
                     "(Get_Error) 0x00000200 DC_BUS_UNDER_VOLTAGE"),
            std::string::npos)
      << why;
  rig.device->clear_fault();  // Clear_Errors: the disarm reason goes
  EXPECT_TRUE(eventually([&] { return axis.disarm_reason() == 0u; })) << axis.disarm_reason();
  ASSERT_NO_THROW(rig.device->enable());
  EXPECT_EQ(rig.run(0.5, 200), IoStatus::kOk) << rig.device->describe_fault();
  EXPECT_EQ(axis.unmodelled_mode_passes(), 0u);
}

// An axis that also sends Get_Error by itself (error_msg_rate_ms): those messages are the
// driver's (no unknown ids), and the disarm is named by the reason, not by one sent before it.
TEST(CanReferenceOdrive, Firmware06SendingGetErrorByItselfIsUnderstood) {
  reference::Odrive06Config c;
  c.error_msg_rate_ms = 20;
  reference::Odrive06 axis(c, still_axis(), reference::monotonic_ns());
  ReferenceRig rig(odrive_config({"device.can.odrive.vel_limit=0"}), axis);
  ASSERT_NO_THROW(rig.device->configure());
  ASSERT_NO_THROW(rig.device->enable());
  ASSERT_EQ(rig.run(0.5, 300), IoStatus::kOk) << rig.device->describe_fault();
  axis.dip_dc_bus(20);
  ASSERT_EQ(rig.run(0.5, 1000), IoStatus::kDeviceFault);
  rig.device->disable();
  const std::string why = rig.device->describe_fault();
  EXPECT_NE(why.find("disarm reason (Get_Error) 0x00000200 DC_BUS_UNDER_VOLTAGE"),
            std::string::npos)
      << why;
  EXPECT_EQ(counter(*rig.device, "unknown_ids").value(), 0u);
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
