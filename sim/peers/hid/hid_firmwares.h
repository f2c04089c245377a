// The two firmwares behind make_firmware() (hid_firmware.h).
#pragma once

#include <memory>

#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::sim::hid {

std::unique_ptr<HidFirmware> make_report_firmware(const config::Config& cfg,
                                                  const drivers::hid::HidSettings& s,
                                                  int link_delay);
std::unique_ptr<HidFirmware> make_pid_firmware(const config::Config& cfg,
                                               const drivers::hid::HidSettings& s, int link_delay);

}  // namespace hapticd::sim::hid
