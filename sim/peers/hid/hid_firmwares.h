// The two firmwares behind make_firmware() (hid_firmware.h).
#pragma once

#include <memory>

#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::sim::hid {

std::unique_ptr<HidFirmware> make_report_firmware(const config::Config& cfg,
                                                  const drivers::hid::HidSettings& s,
                                                  int link_delay);
// How a simulated PID device departs from the complete HID PID 1.0 device it is by default.
struct PidFirmwareOptions {
  // As the SideWinder-lineage firmwares (adapt-ffb-joy and its descendants: YukMingLaw's
  // ArduinoJoystickWithFFBLibrary v1.0.0, jmriego/Fino, VNWheel) are: Device Control a 0x96
  // collection with no 0x95 report around it; one id shared by reports of different kinds
  // (drivers/hid/descriptor_builder.h, kSideWinderLineageIds); a PID State report declared and
  // never sent; Block Load answered once after Create New Effect and with report id 0 after
  // that (DynamicHID_::GetReport sets pidBlockLoad.reportId = 0 once it has sent it); and a
  // positive magnitude at Direction d pushing +sin(d) along X (Joystick.cpp, getEffectForce).
  bool sidewinder_lineage = false;
};

std::unique_ptr<HidFirmware> make_pid_firmware(const config::Config& cfg,
                                               const drivers::hid::HidSettings& s, int link_delay,
                                               const PidFirmwareOptions& options = {});

}  // namespace hapticd::sim::hid
