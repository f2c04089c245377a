#include "drivers/can/can_driver.h"
#include "drivers/can/can_settings.h"

namespace hapticd::drivers::can {

// The configured interface's bitrate and nothing else: a virtual bus has none to set.
void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const auto& s = can_settings(cfg);
  out.literal("device.can.interface", s.interface);
  if (s.interface.rfind("vcan", 0) == 0 || s.interface.rfind("vxcan", 0) == 0) {
    out.comment("device.can.interface " + s.interface +
                " is a virtual bus: it has no bitrate, and udev has nothing to set.");
    return;
  }
  const std::string rate = std::to_string(s.bitrate);
  out.comment("device.can: " + s.interface + ", and no other interface, at " + rate +
              " bit/s (device.can.bitrate) with restart-ms 100 (the controller recovers from "
              "bus-off by itself; hapticd still faults on it), brought up as it appears.");
  out.rule("ACTION==\"add\", SUBSYSTEM==\"net\", KERNEL==\"" + s.interface +
           "\", ATTR{type}==\"280\", RUN+=\"/sbin/ip link set " + s.interface +
           " type can bitrate " + rate + " restart-ms 100\", RUN+=\"/sbin/ip link set " +
           s.interface + " up\"");
}

}  // namespace hapticd::drivers::can
