// device.serial: the serial driver's section (docs/drivers/serial.md, config/serial-*.yaml),
// read with the config library's schema reader so its messages read
// "FILE:LINE: device.serial.x: what". Plain values; pure.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "config/driver_schema.h"
#include "drivers/driver_context.h"
#include "drivers/serial/serial_frame.h"

namespace hapticd::drivers::serial {

// How frames flow. request: each tick hapticd sends one output frame and the device answers
// it with one input frame (Haply's boards; a device that speaks only when spoken to). stream:
// the device sends input frames at its own rate whatever hapticd sends, and takes an output
// frame a tick.
enum class Exchange : std::uint8_t { kRequest, kStream };

// The baud rates a port may be set to (termios' B constants); a USB CDC-ACM device ignores it.
inline constexpr std::uint32_t kBaudRates[] = {9600,    19200,   38400,   57600,  115200,
                                               230400,  460800,  500000,  921600, 1000000,
                                               1500000, 2000000, 3000000, 4000000};

struct SerialSettings final : config::DriverSettings {
  // The port: /dev/ttyACM0, /dev/ttyUSB0, or better a /dev/serial/by-id/ link, which names the
  // device rather than the order it was plugged in.
  std::string port;
  std::uint32_t baud = 115200;
  Exchange exchange = Exchange::kRequest;
  // One way through the port, at worst (ms): a full-speed USB device's polling interval (1),
  // an FTDI port's latency timer. The declared delay is made of it, and hapticd refuses an
  // FTDI port whose timer is longer.
  double latency_ms = 1.0;
  // No good frame for this long: the port is silent (a hung firmware, a cable pulled), a
  // transport fault.
  double liveness_ms = 100.0;
  // The first good frame after opening, within this long, or configure fails.
  double answer_timeout_ms = 1000.0;
  int out_full_fault = 10;  // ticks in a row the port would not take a whole frame
  // Frames sent once as the port opens, in order, startup_gap_ms apart (a reset, the board's
  // parameters): raw bytes.
  std::vector<std::vector<std::uint8_t>> startup;
  double startup_gap_ms = 10.0;
  InputLayout input;
  OutputLayout output;
};

// The device entry's read_section for device.serial.
std::shared_ptr<const config::DriverSettings> read_serial_section(
    config::schema::MapReader& section, const config::Config& cfg);

// The settings of a configuration whose driver is serial (std::logic_error otherwise).
const SerialSettings& serial_settings(const DriverContext& ctx);

// Whole samples between write() and the force acting, as the gate analyses them: a round trip
// through a port of one-way latency latency_ms (round_trip_delay_samples, driver_context.h;
// docs/drivers/serial.md).
int declared_delay_samples(const SerialSettings& s, double sample_period_s) noexcept;

}  // namespace hapticd::drivers::serial
