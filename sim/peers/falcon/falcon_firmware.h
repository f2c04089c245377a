// The simulated Falcon's running firmware (docs/drivers/falcon.md, "The packets"): each 16-byte
// command packet the host sends sets the three motors' torques, steps the mechanism of
// device.kinematics (the delta: its joints are the arms' angles, libnifalcon's theta) one period
// and is answered by one state packet of the three encoders, read through the driver's own codec
// (a command packet has a state packet's layout, so decode_state reads its motor counts and its
// byte 13). The loopback's time is the host's packets, as in the other peers.
//
// The motors: tau_i = counts_i / kCountsPerNewtonMetre, the firmware's own fixed sign, whatever
// the host's device.falcon.counts_per_newton_metre says (a user who flips that setting feels the
// force reversed). The amplifier is on while any count is nonzero (the Falcon has no enable
// switch; as the serial peer's board without one).
//
// Homing, simply: the encoders count from the firmware's start, read here as the arm's counts
// plus a fixed offset (kUnhomedOffsetCounts), so a host that uses them unhomed is caught. The
// simulated person pulls the grip out and in as soon as the commands carry the homing bit: after
// `homing_packets` packets with it in a row the index marks are passed, the offset is gone for
// good (the counters were zeroed at the marks) and the homed bits (4-6 of byte 13) read set for
// as long as every packet keeps the homing bit (libnifalcon: "the homing mode bit must be set in
// each input packet sent in order for the falcon to stay homed"); one packet without it clears
// them, and homing again takes `homing_packets` packets.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "config/config.h"
#include "drivers/falcon/falcon_protocol.h"
#include "sim/mechanism.h"

namespace hapticd::sim::falcon {

inline constexpr int kUnhomedOffsetCounts = 1000;

class FalconFirmware {
 public:
  // Not RT-safe. Throws std::invalid_argument as Mechanism does.
  FalconFirmware(const config::DeviceConfig& device, double sample_period_s, int homing_packets);

  // The load started it: encoders relative again, nothing homed, the amplifier off.
  void start() noexcept;
  // The microcontroller reset (a DTR pulse): the motors stop. The arms stay where they are.
  void stop() noexcept;
  // The host purged its OUT data: a partial packet is dropped.
  void drop_input() noexcept { stream_.clear(); }

  // Data bytes from the host: each complete command packet taken (the mechanism stepped) and
  // its answer appended to `answers`. A packet with a byte out of range is counted, not taken.
  void receive(std::span<const unsigned char> data, std::vector<drivers::falcon::Packet>& answers);

  // The largest torque a motor puts on the mechanism (N m), and whether the amplifier is on.
  double felt_torque() const noexcept { return felt_; }
  bool amplifier_on() const noexcept { return on_; }
  std::uint8_t leds() const noexcept { return leds_; }  // the last command's Led bits
  bool homed() const noexcept { return homed_; }
  std::uint64_t packets_taken() const noexcept { return taken_; }
  std::uint64_t bad_packets() const noexcept { return bad_; }
  std::uint64_t skipped_bytes() const noexcept { return stream_.skipped_bytes(); }
  const Mechanism& mechanism() const noexcept { return mechanism_; }

 private:
  void take(const drivers::falcon::State& command) noexcept;
  void home(bool homing_bit) noexcept;
  drivers::falcon::Packet state_packet() noexcept;

  Mechanism mechanism_;
  drivers::falcon::PacketStream stream_;
  int homing_packets_;
  int homing_seen_ = 0;   // packets with the homing bit in a row
  bool relative_ = true;  // the encoders still count from the start (offset)
  bool homed_ = false;
  bool on_ = false;
  double felt_ = 0.0;
  std::uint8_t leds_ = 0;
  std::uint64_t taken_ = 0;
  std::uint64_t bad_ = 0;
};

}  // namespace hapticd::sim::falcon
