// The bus load a configuration needs (`hapticd check`; above 1 device.can's reader refuses
// it): the frames each tick puts on the bus for the profile and every node (CiA 402: one SYNC
// for the whole bus), their worst-case length with bit stuffing, and the fraction of the
// bitrate that takes at the loop rate. Pure arithmetic.
#pragma once

#include <string>
#include <vector>

#include "drivers/can/can_settings.h"

namespace hapticd::drivers::can {

// Worst-case bits of a classic frame with an 11-bit id and `data_bytes` of data, interframe
// space included: 47 + 8n fixed bits plus one stuff bit per four of the 34 + 8n stuffed ones
// (SOF to CRC), the bound of Davis, Burns, Bril & Lukkien (Real-Time Systems, 2007).
int worst_case_frame_bits(int data_bytes) noexcept;

struct BusLoad {
  double frames_per_tick = 0.0;     // heartbeats counted at their share of a tick
  double bits_per_tick = 0.0;       // worst case, with stuffing
  double load = 0.0;                // bits per second over the bitrate
  std::vector<std::string> frames;  // "SYNC (0 bytes)", ...
};
BusLoad bus_load(const CanSettings& s, double rate_hz);

// Not RT-safe. The sentence refusing a configuration whose load is above 1: the load, the
// frames per tick, the rate and the bitrate, and what would fit (device.can's reader says it).
std::string bus_load_refusal(const CanSettings& s, double rate_hz, const BusLoad& load);

// The lines `check` prints (and puts in --json): the load and, above bus_load_warn, a warning.
std::vector<std::string> bus_load_notes(const CanSettings& s, double rate_hz);

}  // namespace hapticd::drivers::can
