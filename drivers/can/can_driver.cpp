#include "drivers/can/can_driver.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "base/errno_text.h"
#include "config/schema_reader.h"
#include "drivers/can/can_bus_load.h"
#include "drivers/can/can_device.h"
#include "drivers/can/canopen.h"
#include "drivers/can/odrive_protocol.h"

namespace hapticd::drivers::can {
namespace {

std::unique_ptr<Device> can_loopback_device(const DriverContext& ctx, io::UniqueFd end) {
  // The device keeps the pair's end and hands its transport a duplicate at each configure,
  // so closing and configuring again works like unplugging and replugging a cable.
  auto kept = std::make_shared<io::UniqueFd>(std::move(end));
  auto open = [kept] {
    const int fd = ::fcntl(kept->get(), F_DUPFD_CLOEXEC, 0);
    if (fd < 0) throw DeviceError("can: loopback: dup: " + base::errno_text(errno));
    return CanSocket::adopt(io::UniqueFd(fd), "loopback");
  };
  if (!ctx.realtime) return make_can_device(ctx, std::move(open));
  // The simulated drive answers at once unless the host holds its thread up: configure's
  // waits (an SDO answer, a heartbeat, a state) get seconds, not the bus's milliseconds.
  CanSettings s = can_settings(ctx);
  s.sdo_timeout_ms = std::max(s.sdo_timeout_ms, 2000);
  s.state_timeout_ms = std::max(s.state_timeout_ms, 5000);
  s.heartbeat_timeout_ms = std::max(s.heartbeat_timeout_ms, 2000);
  return std::make_unique<CanDevice>(s, ctx.sample_period_s(), std::move(open), ctx.rt_priority);
}

// The frames the driver of a profile needs to see, of every node.
std::vector<IdFilter> receive_filters(const CanSettings& s) {
  std::vector<IdFilter> filters;
  for (const CanNode& node : s.nodes) {
    const std::uint32_t n = node.node_id;
    if (s.profile == Profile::kOdrive) {
      filters.push_back({odrive::frame_id(node.node_id, 0), 0x7E0});  // its 32 command ids
      continue;
    }
    for (std::uint32_t base : {canopen::kTpdo1Base, canopen::kTpdo2Base, canopen::kEmcyBase,
                               canopen::kSdoTxBase, canopen::kHeartbeatBase}) {
      filters.push_back({base + n});
    }
  }
  return filters;
}

std::unique_ptr<Device> can_device(const DriverContext& ctx) {
  const CanSettings& s = can_settings(ctx);
  const std::vector<IdFilter> filters = receive_filters(s);
  return make_can_device(ctx, [interface = s.interface, filters] {
    return CanSocket::open_interface(interface, filters, true);
  });
}

std::vector<std::string> can_notes(const DriverContext& ctx) {
  std::vector<std::string> notes = bus_load_notes(can_settings(ctx), ctx.rate_hz());
  if (const std::string v = odrive_speed_note(can_settings(ctx)); !v.empty()) notes.push_back(v);
  return notes;
}

// The transmission's sign: a motor mounted to turn the axis the other way (docs/drivers/can.md).
ForceReversal force_reversal(const config::Config& cfg) {
  using config::schema::format_number;
  // Joint 0's (the direction check drives one joint); where several nodes are, its own entry
  // (or the section's default it took) is the one to change.
  const CanSettings& s = can_settings(cfg);
  const double k = s.nodes.front().torque_per_force;
  return {
      s.nodes.size() > 1 ? "device.can.nodes[0].torque_per_force" : "device.can.torque_per_force",
      format_number(k), format_number(-k)};
}

}  // namespace

std::unique_ptr<Device> make_can_device(const DriverContext& ctx, std::function<CanSocket()> open) {
  // A stop keeps SYNC going on the loop's clock: at its priority where the loop runs in real time.
  const int keeper = ctx.realtime ? ctx.rt_priority : 0;
  return std::make_unique<CanDevice>(can_settings(ctx), ctx.sample_period_s(), std::move(open),
                                     keeper);
}

DeviceEntry device_entry() {
  DeviceEntry e;
  e.udev_rules = &write_udev_rules;
  e.name = "can";
  e.summary = "SocketCAN: a CiA 402 drive (cyclic synchronous torque) or an ODrive (CAN Simple)";
  e.read_section = &read_can_section;
  e.declared_delay = &declared_delay;
  e.make_device = &can_device;
  e.make_loopback_device = &can_loopback_device;
  e.notes = &can_notes;
  e.force_reversal = &force_reversal;
  return e;
}

}  // namespace hapticd::drivers::can
