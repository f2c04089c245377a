#include "sim/peers/falcon/falcon_firmware.h"

#include <algorithm>
#include <cmath>

namespace hapticd::sim::falcon {
namespace {

namespace df = drivers::falcon;

constexpr unsigned char kNibbleBase = 0x41;  // each nibble is sent plus 'A'

}  // namespace

FalconFirmware::FalconFirmware(const config::DeviceConfig& device, double sample_period_s,
                               int homing_packets)
    : mechanism_(device, sample_period_s), homing_packets_(std::max(1, homing_packets)) {}

void FalconFirmware::start() noexcept {
  stop();
  stream_.clear();
  relative_ = true;
  homed_ = false;
  homing_seen_ = 0;
  leds_ = 0;
}

void FalconFirmware::stop() noexcept {
  for (int j = 0; j < mechanism_.joints(); ++j) mechanism_.set_output(j, false);
  on_ = false;
  felt_ = 0.0;
}

void FalconFirmware::receive(std::span<const unsigned char> data,
                             std::vector<df::Packet>& answers) {
  stream_.feed_data(data);
  df::Packet p;
  while (stream_.next(p)) {
    df::State command;
    if (df::decode_state(p, command) != df::PacketError::kNone) {
      ++bad_;  // the firmware drops what it cannot read: no step, no answer
      continue;
    }
    take(command);
    answers.push_back(state_packet());
  }
}

void FalconFirmware::take(const df::State& command) noexcept {
  // decode_state read byte 13's low nibble as `grip`: a command's homing and LED bits.
  const std::uint8_t flags = command.grip;
  leds_ = static_cast<std::uint8_t>(flags & (df::kLedGreen | df::kLedBlue | df::kLedRed));
  home((flags & 0x1) != 0);
  const bool on = std::ranges::any_of(command.encoder, [](std::int16_t c) { return c != 0; });
  felt_ = 0.0;
  for (int j = 0; j < mechanism_.joints(); ++j) {
    if (mechanism_.output_on(j) != on) mechanism_.set_output(j, on);
    mechanism_.hold_torque(
        j, command.encoder[static_cast<std::size_t>(j)] / df::kCountsPerNewtonMetre);
    felt_ = std::max(felt_, std::abs(mechanism_.held_torque(j)));
  }
  on_ = on;
  mechanism_.step();
  ++taken_;
}

void FalconFirmware::home(bool homing_bit) noexcept {
  if (!homing_bit) {
    homing_seen_ = 0;
    homed_ = false;
    return;
  }
  if (homing_seen_ < homing_packets_) ++homing_seen_;
  if (homing_seen_ == homing_packets_) {
    homed_ = true;
    relative_ = false;  // the index marks passed: the counters were zeroed there
  }
}

df::Packet FalconFirmware::state_packet() noexcept {
  // The codec has no state encoder (the host never sends one): a command's layout is the
  // state's, with byte 13 widened to the homed bits.
  df::Command as_command;
  for (int j = 0; j < 3; ++j) {
    const double q = j < mechanism_.joints() ? mechanism_.encoder_position(j) : 0.0;
    int counts = df::counts_at_angle(q);
    if (relative_) counts += kUnhomedOffsetCounts;
    as_command.motor[static_cast<std::size_t>(j)] =
        static_cast<std::int16_t>(static_cast<std::uint16_t>(counts));
  }
  df::Packet p = df::encode_command(as_command);
  const unsigned homed_bits = homed_ ? 0x7u : 0x0u;
  p[13] = static_cast<unsigned char>(kNibbleBase + (homed_bits << 4));  // grip: no button
  return p;
}

}  // namespace hapticd::sim::falcon
