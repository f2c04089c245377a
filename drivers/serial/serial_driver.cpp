#include "drivers/serial/serial_driver.h"

#include "drivers/serial/serial_device.h"
#include "drivers/serial/tty_port.h"

namespace hapticd::drivers::serial {
namespace {

int delay(const DriverContext& ctx) {
  return declared_delay_samples(serial_settings(ctx), ctx.sample_period_s());
}

std::shared_ptr<const SerialSettings> settings_of(const DriverContext& ctx) {
  return std::dynamic_pointer_cast<const SerialSettings>(ctx.settings);
}

std::unique_ptr<Device> make_device(const DriverContext& ctx) {
  auto s = settings_of(ctx);
  (void)serial_settings(ctx);  // the right section, or std::logic_error
  const double period = ctx.sample_period_s();
  auto open = [s, period] {
    OpenedPort p = open_tty(*s);
    check_wire_rate(*s, tty_driver(tty_name(s->port)), period);
    return Port{std::move(p.fd), true, std::move(p.notices)};
  };
  return std::make_unique<SerialDevice>(s, open, ctx.sample_period_s(), s->input.positions.size());
}

// The loopback socketpair holds the peer's frames as messages: read until none is left.
std::unique_ptr<Device> make_loopback_device(const DriverContext& ctx, io::UniqueFd end) {
  auto s = settings_of(ctx);
  (void)serial_settings(ctx);
  auto shared = std::make_shared<io::UniqueFd>(std::move(end));
  auto open = [shared] {
    if (!*shared)
      throw DeviceError("serial loopback: the socketpair was closed (one configure per pair)");
    return Port{std::move(*shared), false, {}};
  };
  return std::make_unique<SerialDevice>(s, open, ctx.sample_period_s(), s->input.positions.size());
}

// One field as the configuration writes it (field_schema.h), in YAML's flow style.
std::string flow(const FieldSpec& f, double scale) {
  using config::schema::format_number;
  std::string s = "{byte: " + std::to_string(f.byte);
  const std::string type = field::type_name(f);
  if (field::parse_field_type(type)) {
    s += ", type: " + type;
  } else {
    s += ", bits: " + std::to_string(f.bits) + (f.is_signed ? ", signed: true" : "");
  }
  if (f.bit != 0) s += ", bit: " + std::to_string(f.bit);
  if (f.endian == field::Endian::kBig) s += ", endian: big";
  s += ", scale: " + format_number(scale);
  if (f.offset != 0.0) s += ", offset: " + format_number(f.offset);
  return s + "}";
}

// The force fields' scales: their sign is the direction of the force the device is sent, so
// the list with every scale negated reverses it (on every joint).
ForceReversal force_reversal(const config::Config& cfg) {
  std::string now = "[", reversed = "[";
  for (const FieldSpec& f : serial_settings(cfg).output.forces) {
    const char* sep = now.size() > 1 ? ", " : "";
    now += sep + flow(f, f.scale);
    reversed += sep + flow(f, -f.scale);
  }
  return {"device.serial.output.forces", now + "]", reversed + "]"};
}

}  // namespace

DeviceEntry device_entry() {
  DeviceEntry e;
  e.name = "serial";
  e.summary = "a device on a USB serial port (CDC-ACM ttyACM, FTDI ttyUSB) in configured frames";
  e.read_section = &read_serial_section;
  e.declared_delay = &delay;
  e.make_device = &make_device;
  e.make_loopback_device = &make_loopback_device;
  e.list_devices = &list_ports;
  e.force_reversal = &force_reversal;
  e.udev_rules = &write_udev_rules;
  return e;
}

}  // namespace hapticd::drivers::serial
