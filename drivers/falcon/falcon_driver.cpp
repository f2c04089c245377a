#include "drivers/falcon/falcon_driver.h"

#include "config/schema_reader.h"
#include "drivers/falcon/falcon_device.h"
#include "drivers/falcon/socket_link.h"
#include "drivers/falcon/usb_link.h"
#include "drivers/io/output_thread.h"

namespace hapticd::drivers::falcon {
namespace {

int delay(const DriverContext& ctx) {
  (void)falcon_settings(ctx);  // the right section, or std::logic_error
  return declared_delay_samples(ctx.sample_period_s());
}

std::shared_ptr<const FalconSettings> settings_of(const DriverContext& ctx) {
  (void)falcon_settings(ctx);
  return std::dynamic_pointer_cast<const FalconSettings>(ctx.settings);
}

std::unique_ptr<Device> make_device(const DriverContext& ctx) {
  auto s = settings_of(ctx);
  const int priority = io::output_thread_priority(ctx.rt_priority);
  auto open = [s, priority] { return open_usb(*s, priority); };
  return std::make_unique<FalconDevice>(s, open, ctx.sample_period_s());
}

std::unique_ptr<Device> make_loopback_device(const DriverContext& ctx, io::UniqueFd end) {
  auto s = settings_of(ctx);
  auto shared = std::make_shared<io::UniqueFd>(std::move(end));
  auto open = [shared]() -> std::unique_ptr<FalconTransport> {
    if (!*shared) throw DeviceError("falcon loopback: the socketpair was closed (one configure)");
    return std::make_unique<SocketLink>(std::move(*shared));
  };
  return std::make_unique<FalconDevice>(s, open, ctx.sample_period_s());
}

// The counts' sign is the direction the firmware turns an arm for a positive command.
ForceReversal force_reversal(const config::Config& cfg) {
  const double k = falcon_settings(cfg).counts_per_newton_metre;
  return {"device.falcon.counts_per_newton_metre", config::schema::format_number(k),
          config::schema::format_number(-k)};
}

}  // namespace

void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const FalconSettings& s = falcon_settings(cfg);
  std::string match = "SUBSYSTEM==\"usb\", ENV{DEVTYPE}==\"usb_device\", ATTR{idVendor}==\"" +
                      usb_id(kVendorId) + "\", ATTR{idProduct}==\"" + usb_id(kProductId) + "\"";
  if (!s.serial.empty()) {
    out.literal("device.falcon.serial", s.serial);
    match += ", ATTR{serial}==\"" + s.serial + "\"";
  }
  out.comment("device.falcon: the Novint Falcon (0403:cb48" +
              (s.serial.empty() ? std::string() : ", serial " + s.serial) +
              "), its USB device node granted to the group. hapticd claims it through libusb and "
              "detaches ftdi_sio from it while it runs, if the kernel bound that.");
  out.rule(match + out.grant());
}

DeviceEntry device_entry() {
  DeviceEntry e;
  e.name = "falcon";
  e.summary = "a Novint Falcon (FTDI 0403:cb48) over libusb, Novint's firmware loaded";
  e.read_section = &read_falcon_section;
  e.declared_delay = &delay;
  e.make_device = &make_device;
  e.make_loopback_device = &make_loopback_device;
  e.list_devices = &list_falcons;
  e.force_reversal = &force_reversal;
  e.udev_rules = &write_udev_rules;
  return e;
}

}  // namespace hapticd::drivers::falcon
