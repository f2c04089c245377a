#include "drivers/hid/hid_driver.h"

#include <fcntl.h>

#include <cerrno>
#include <cmath>

#include "base/errno_text.h"
#include "config/schema_reader.h"
#include "drivers/hid/hid_device.h"
#include "drivers/hid/hidapi_transport.h"
#include "drivers/hid/socket_transport.h"

namespace hapticd::drivers::hid {
namespace {

std::shared_ptr<const HidSettings> settings_of(const DriverContext& ctx) {
  auto s = std::dynamic_pointer_cast<const HidSettings>(ctx.settings);
  if (!s) throw DeviceError("hid: the configuration has no device.hid section");
  return s;
}

int declared_delay(const DriverContext& ctx) {
  return declared_delay_samples(*settings_of(ctx), ctx.sample_period_s());
}

std::unique_ptr<Device> make_device(const DriverContext& ctx) {
  auto s = settings_of(ctx);
  return std::make_unique<HidDevice>(
      s, [s] { return open_hidapi(*s); }, ctx.sample_period_s());
}

std::unique_ptr<Device> make_loopback_device(const DriverContext& ctx, io::UniqueFd end) {
  auto s = settings_of(ctx);
  // The device opens a duplicate at each configure, so it can be closed and configured again.
  auto kept = std::make_shared<io::UniqueFd>(std::move(end));
  const std::chrono::milliseconds timeout(static_cast<long>(s->limits.timeout_ms));
  auto open = [kept, timeout]() -> std::unique_ptr<HidTransport> {
    io::UniqueFd fd(fcntl(kept->get(), F_DUPFD_CLOEXEC, 0));
    if (!fd) throw DeviceError("hid loopback: dup: " + base::errno_text(errno));
    return std::make_unique<SocketTransport>(std::move(fd), timeout);
  };
  return std::make_unique<HidDevice>(s, std::move(open), ctx.sample_period_s());
}

// A force field as the configuration writes it, with `scale` for its scale.
std::string flow(const ForceField& f, double scale) {
  using config::schema::format_number;
  const FieldSpec& s = f.field;
  std::string out = "{byte: " + std::to_string(s.byte);
  const std::string type = field::type_name(s);
  if (field::parse_field_type(type)) {
    out += ", type: " + type;
  } else {
    out += ", bits: " + std::to_string(s.bits) + (s.is_signed ? ", signed: true" : "");
  }
  if (s.bit != 0) out += ", bit: " + std::to_string(s.bit);
  if (s.endian == field::Endian::kBig) out += ", endian: big";
  out += ", scale: " + format_number(scale);
  if (s.offset != 0.0) out += ", offset: " + format_number(s.offset);
  return out + ", full_scale: " + format_number(f.full_scale) + "}";
}

// The PID profile's Direction turns by half a turn; the report profile's force field changes
// its sign (docs/drivers/hid.md, which way a positive level pushes).
ForceReversal force_reversal(const config::Config& cfg) {
  using config::schema::format_number;
  const HidSettings& s = *settings_of(cfg);
  if (s.profile == Profile::kPid && s.pid.directions_deg.empty()) {
    return {"device.hid.pid.direction_deg", format_number(s.pid.direction_deg),
            format_number(std::fmod(s.pid.direction_deg + 180.0, 360.0))};
  }
  if (s.profile == Profile::kPid) {
    // Two axes: each Direction read along its axis, mirrored about its range's middle.
    std::string now = "[", reversed = "[";
    for (std::size_t j = 0; j < s.pid.directions_deg.size(); ++j) {
      const char* sep = j > 0 ? ", " : "";
      now += sep + format_number(s.pid.directions_deg[j]);
      reversed += sep + format_number(360.0 - s.pid.directions_deg[j]);
    }
    return {"device.hid.pid.directions_deg", now + "]", reversed + "]"};
  }
  const OutputLayout& o = s.report.output;
  if (!o.listed) {
    const double scale = o.force.scale;
    return {"device.hid.report.output.force.scale", format_number(scale), format_number(-scale)};
  }
  // The list form: the whole list, every entry as it is but its scale's sign, so the value
  // given back with --set is a list the configuration reads.
  std::string now = "[", reversed = "[";
  for (std::size_t j = 0; j < o.joints(); ++j) {
    const char* sep = j > 0 ? ", " : "";
    const ForceField f = o.joint(j);
    now += sep + flow(f, f.field.scale);
    reversed += sep + flow(f, -f.field.scale);
  }
  return {"device.hid.report.output.forces", now + "]", reversed + "]"};
}

std::string list_devices() {
  std::string out;
  for (Backend b : {Backend::kHidraw, Backend::kLibusb}) {
    out += std::string("hid (") + to_string(b) + " backend):\n";
    try {
      out += format_listing(enumerate_devices(b), to_string(b));
    } catch (const DeviceError& e) {
      out += std::string("  cannot enumerate: ") + e.what() + "\n";
    }
  }
  return out;
}

}  // namespace

DeviceEntry device_entry() {
  DeviceEntry e;
  e.udev_rules = &write_udev_rules;
  e.name = "hid";
  e.summary = "USB HID through hidapi (hidraw or libusb): vendor reports or the PID page";
  e.read_section = read_hid_section;
  e.declared_delay = &declared_delay;
  e.make_device = &make_device;
  e.make_loopback_device = &make_loopback_device;
  e.list_devices = &list_devices;
  e.force_reversal = &force_reversal;
  return e;
}

}  // namespace hapticd::drivers::hid
