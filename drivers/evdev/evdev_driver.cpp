#include "drivers/evdev/evdev_driver.h"

#include <fcntl.h>

#include <cerrno>
#include <cmath>

#include "base/errno_text.h"
#include "config/schema_reader.h"
#include "drivers/evdev/evdev_config.h"
#include "drivers/evdev/evdev_device.h"
#include "drivers/evdev/libevdev_transport.h"
#include "drivers/evdev/socket_transport.h"

namespace hapticd::drivers::evdev {
namespace {

std::shared_ptr<const EvdevSettings> settings_of(const DriverContext& ctx) {
  auto s = std::dynamic_pointer_cast<const EvdevSettings>(ctx.settings);
  if (!s) throw DeviceError("evdev: the configuration has no device.evdev section");
  return s;
}

int declared_delay(const DriverContext& ctx) {
  return declared_delay_samples(*settings_of(ctx), ctx.sample_period_s());
}

std::unique_ptr<Device> make_device(const DriverContext& ctx) {
  auto s = settings_of(ctx);
  auto open = [s] {
    EvdevDevice::Opened o;
    InputListing listing;
    o.transport = open_libevdev(*s, listing);
    o.listing = listing;
    return o;
  };
  return std::make_unique<EvdevDevice>(s, std::move(open), ctx.sample_period_s(), ctx.realtime);
}

std::unique_ptr<Device> make_loopback_device(const DriverContext& ctx, io::UniqueFd end) {
  auto s = settings_of(ctx);
  // The device opens a duplicate at each configure, so it can be closed and configured again.
  auto kept = std::make_shared<io::UniqueFd>(std::move(end));
  auto open = [kept] {
    io::UniqueFd fd(fcntl(kept->get(), F_DUPFD_CLOEXEC, 0));
    if (!fd) throw DeviceError("evdev loopback: dup: " + base::errno_text(errno));
    EvdevDevice::Opened o;
    o.transport = std::make_unique<SocketTransport>(std::move(fd), std::chrono::seconds(2));
    return o;
  };
  return std::make_unique<EvdevDevice>(s, std::move(open), ctx.sample_period_s(), ctx.realtime);
}

std::vector<std::string> notes(const DriverContext& ctx) {
  const EvdevSettings& s = *settings_of(ctx);
  std::string line = "evdev: ff_driver " + std::string(to_string(s.ff_driver)) + ": " +
                     std::to_string(declared_delay(ctx)) + " samples of delay declared";
  const double highest = highest_rate_hz(s);
  if (highest > 0.0) {
    line += ", at most " + config::schema::format_number(highest) +
            " updates a second reach the device";
  }
  if (s.joints == 2) {
    line += "; two axes, " + abs_name(s.axis.code) + " and " + abs_name(s.second.code) +
            ", effect " + to_string(s.effect) +
            (s.effect == EffectMode::kDirection
                 ? " (one EVIOCSFF a tick, its direction following the force)"
                 : " (one effect per axis: two EVIOCSFF a tick)");
  }
  return {line + " (docs/drivers/evdev.md)"};
}

std::string list_devices() {
  try {
    const Enumeration e = enumerate_input_devices();
    return format_listing(e.devices, e.unreadable);
  } catch (const std::exception& e) {
    return std::string("evdev:\n  cannot enumerate /dev/input: ") + e.what() + "\n";
  }
}

// The effect's direction turned by half a turn (docs/drivers/evdev.md); with two axes joint
// 0's (the direction check drives one joint).
ForceReversal force_reversal(const config::Config& cfg) {
  using config::schema::format_number;
  const EvdevSettings& s = *settings_of(cfg);
  const double d = s.joints == 1 ? s.direction_deg : s.axis.direction_deg;
  return {s.joints == 1 ? "device.evdev.direction_deg" : "device.evdev.axes[0].direction_deg",
          format_number(d), format_number(std::fmod(d + 180.0, 360.0))};
}

}  // namespace

DeviceEntry device_entry() {
  DeviceEntry e;
  e.udev_rules = &write_udev_rules;
  e.name = "evdev";
  e.summary = "an input device with force feedback through the kernel's evdev interface";
  e.read_section = read_evdev_section;
  e.declared_delay = &declared_delay;
  e.make_device = &make_device;
  e.make_loopback_device = &make_loopback_device;
  e.notes = &notes;
  e.list_devices = &list_devices;
  e.force_reversal = &force_reversal;
  return e;
}

}  // namespace hapticd::drivers::evdev
