// device.falcon: the Falcon driver's section (docs/drivers/falcon.md, config/falcon.yaml), read
// with the config library's schema reader so its messages read "FILE:LINE: device.falcon.x:
// what". Plain values; pure.
#pragma once

#include <memory>
#include <string>

#include "config/driver_schema.h"
#include "drivers/driver_context.h"
#include "drivers/falcon/falcon_protocol.h"

namespace hapticd::drivers::falcon {

struct FalconSettings final : config::DriverSettings {
  // Novint's firmware image, an absolute path (hapticd never ships it).
  std::string firmware;
  // The FT232's serial number (`hapticd devices` lists it); empty: the one Falcon attached.
  std::string serial;
  int load_tries = 3;  // firmware loads tried before configure gives up
  // Counts of motor command per N m of torque at the arm. Its sign is the direction the
  // firmware turns the arm for a positive count: the one setting that reverses the force.
  double counts_per_newton_metre = kCountsPerNewtonMetre;
  // How long configure waits for the grip to be pulled all the way out and pushed back in,
  // with the LED red, until the firmware reports all three encoders homed.
  double homing_timeout_s = 60.0;
  // No packet back for this long: the device hung or went, a transport fault.
  double liveness_ms = 100.0;
};

// The device entry's read_section for device.falcon. Refuses a device.kinematics other than
// delta and a device.max_force a motor command cannot carry (|max_force x counts| > 32767).
std::shared_ptr<const config::DriverSettings> read_falcon_section(
    config::schema::MapReader& section, const config::Config& cfg);

// The settings of a configuration whose driver is falcon (std::logic_error otherwise).
const FalconSettings& falcon_settings(const DriverContext& ctx);

// Whole samples between write() and the force acting: the firmware answers each packet, so a
// command and its answer each wait up to the 1 ms latency timer (round_trip_delay_samples):
// 1 at 1 kHz.
int declared_delay_samples(double sample_period_s) noexcept;

}  // namespace hapticd::drivers::falcon
