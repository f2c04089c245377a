// The config section device.can (docs/drivers/can.md, config/can-*.yaml): the bus, the node,
// the profile, the transmission between motor and axis, limits and time-outs, and each
// profile's own subsection. Read with the config library's schema reader, so every problem is
// "FILE:LINE: device.can.key: what".
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "config/config.h"
#include "config/schema_reader.h"
#include "drivers/can/cia402.h"
#include "drivers/can/odrive_protocol.h"
#include "drivers/driver_context.h"

namespace hapticd::drivers::can {

enum class Profile : std::uint8_t { kCia402, kOdrive };
enum class PdoMapping : std::uint8_t { kConfigure, kVerify };
enum class PositionSource : std::uint8_t { kRequest, kCyclic };

struct Cia402Settings {
  PdoMapping pdo_mapping = PdoMapping::kConfigure;
  bool map_velocity = false;           // TPDO2 carries 0x606C velocity actual
  int heartbeat_producer_ms = 100;     // 0x1017: how often the drive says it is alive
  std::uint8_t master_node_id = 0x7F;  // the id hapticd's own heartbeat carries
  int master_heartbeat_ms = 20;        // hapticd's heartbeat period; 0: none
  int drive_watchdog_ms = 100;         // 0x1016:1 consumer time: the drive's reaction after
                                       // this long without hapticd's heartbeat; 0: not set
  cia402::CommLossReaction comm_loss_reaction = cia402::CommLossReaction::kDisableVoltage;
  // How long enable waits for a drive that stays in switch on disabled with statusword bit 4
  // (voltage enabled) at 0: its DC link still charging, 1 to 2 s after mains on many drives.
  int dc_link_timeout_ms = 3000;
};

struct OdriveSettings {
  bool detect_firmware = true;  // firmware: auto (Get_Version, 0.5 when it stays silent)
  odrive::Firmware firmware = odrive::Firmware::k06;
  PositionSource position_source = PositionSource::kRequest;
  int cyclic_period_ms = 1;  // encoder rate: 0.5 axis.config.can.encoder_rate_ms, 0.6
                             // axis.config.can.encoder_msg_rate_ms (cyclic)
  int heartbeat_period_ms =
      100;  // 0.5 axis.config.can.heartbeat_rate_ms, 0.6 heartbeat_msg_rate_ms
  // What the axis has in controller.config.vel_limit (turn/s) with enable_torque_mode_vel_limit
  // (brakes above it) and enable_overspeed_error (faults above vel_limit_tolerance times it):
  // the firmware's defaults, 2 turn/s and 1.2; 0: the user switched both off.
  double vel_limit = 2.0;
  double vel_limit_tolerance = 1.2;
  double watchdog_timeout_s = 0.25;  // axis.config.watchdog_timeout the driver relies on
  // 0.6 only: endpoint ids (flat_endpoints.json of the firmware) through which configure
  // writes enable_watchdog and watchdog_timeout and reads them back; 0: set by the user.
  std::uint16_t enable_watchdog_endpoint = 0;
  std::uint16_t watchdog_timeout_endpoint = 0;
};

// One drive (a CiA 402 node, an ODrive axis) and the joint it moves: device.can.node_id with
// the section's transmission, or one entry of device.can.nodes (its own transmission, the
// section's where it gives none).
struct CanNode {
  std::uint8_t node_id = 1;
  double torque_per_force = 1.0;   // motor N m per unit of axis force (N or N m)
  double position_per_unit = 1.0;  // axis m or rad per device position unit
  double max_torque = 1.0;         // |motor torque| the driver never exceeds (N m)
};

struct CanSettings final : config::DriverSettings {
  std::string interface = "can0";
  std::uint32_t bitrate = 1'000'000;
  // Joint i of the device is nodes[i]: one (node_id) to base::kMaxJoints (nodes), on one bus.
  std::vector<CanNode> nodes{CanNode{}};
  Profile profile = Profile::kCia402;
  int sdo_timeout_ms = 100;        // one SDO answer, Get_Version, an endpoint read
  int state_timeout_ms = 500;      // one step of the power state machine / axis state
  int heartbeat_timeout_ms = 300;  // the drive's heartbeat missing this long is a fault
  int tx_full_fault_ticks = 3;     // ticks in a row the TX queue refuses a frame (ENOBUFS)
  double bus_load_warn = 0.7;      // `check` warns above this fraction of the bitrate
  Cia402Settings cia402;
  OdriveSettings odrive;
};

// The settings of one of the nodes alone (a device, or a simulated drive, of one joint).
CanSettings single_node(const CanSettings& s, std::size_t joint);

// Reads device.can (DriverSchema::read_section); null after reporting problems.
std::shared_ptr<const config::DriverSettings> read_can_section(config::schema::MapReader& section,
                                                               const config::Config& cfg);
// The settings of a loaded config whose device.driver is can. Throws DeviceError otherwise.
const CanSettings& can_settings(const DriverContext& ctx);

// Whole samples between write() and the force acting (docs/drivers/can.md): 1 for CiA 402 (an RPDO
// takes effect at the next SYNC) and for ODrive on request (the answer to this tick's request
// is the position the next tick acts on); ceil(period / T) for ODrive's cyclic message.
int declared_delay(const DriverContext& ctx);
int delay_samples(const CanSettings& s, double rate_hz);
// ODrive: the speed above which the firmware brakes (and then faults) in torque control, in
// the axis's own units, as a `check` warning; "" for CiA 402 or with the limit off.
std::string odrive_speed_note(const CanSettings& s);

}  // namespace hapticd::drivers::can
