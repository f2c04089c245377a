#include "drivers/can/can_bus_load.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hapticd::drivers::can {
namespace {

struct Cyclic {
  std::string name;
  int bytes;
  double per_tick;  // 1 for every tick, less for a heartbeat
};

// `copies`: one for the bus, or one per node.
void add(BusLoad& load, const Cyclic& c, double copies) {
  load.frames_per_tick += copies * c.per_tick;
  load.bits_per_tick += copies * c.per_tick * worst_case_frame_bits(c.bytes);
  char text[128];
  if (c.per_tick == 1.0) {
    std::snprintf(text, sizeof text, "%s (%d byte%s)", c.name.c_str(), c.bytes,
                  c.bytes == 1 ? "" : "s");
  } else {
    std::snprintf(text, sizeof text, "%s (%d byte%s, every %.0f ticks)", c.name.c_str(), c.bytes,
                  c.bytes == 1 ? "" : "s", 1.0 / c.per_tick);
  }
  load.frames.emplace_back(text);
}

}  // namespace

int worst_case_frame_bits(int n) noexcept { return 47 + 8 * n + (34 + 8 * n - 1) / 4; }

BusLoad bus_load(const CanSettings& s, double rate_hz) {
  BusLoad load;
  const double period_ms = 1e3 / rate_hz;
  const auto every = [&](int ms) { return ms <= 0 ? 0.0 : std::min(1.0, period_ms / ms); };
  const double n = static_cast<double>(s.nodes.size());
  const auto each = [&](const char* name) {
    return s.nodes.size() == 1 ? std::string(name)
                               : std::string(name) + " x" + std::to_string(s.nodes.size());
  };
  if (s.profile == Profile::kCia402) {
    add(load, {"SYNC", 0, 1.0}, 1.0);  // one for the whole bus
    add(load, {each("RPDO1 controlword + target torque"), 4, 1.0}, n);
    add(load, {each("TPDO1 statusword + position"), 6, 1.0}, n);
    if (s.cia402.map_velocity) add(load, {each("TPDO2 velocity"), 4, 1.0}, n);
    add(load, {each("drive heartbeat"), 1, every(s.cia402.heartbeat_producer_ms)}, n);
    if (s.cia402.master_heartbeat_ms > 0) {
      add(load, {"hapticd heartbeat", 1, every(s.cia402.master_heartbeat_ms)}, 1.0);
    }
  } else {
    add(load, {each("Set_Input_Torque"), 4, 1.0}, n);
    if (s.odrive.position_source == PositionSource::kRequest) {
      add(load, {each("Get_Encoder_Estimates request (RTR)"), 0, 1.0}, n);
      add(load, {each("Get_Encoder_Estimates"), 8, 1.0}, n);
    } else {
      add(load, {each("Get_Encoder_Estimates (cyclic)"), 8, every(s.odrive.cyclic_period_ms)}, n);
    }
    add(load, {each("Heartbeat"), 8, every(s.odrive.heartbeat_period_ms)}, n);
  }
  load.load = load.bits_per_tick * rate_hz / s.bitrate;
  return load;
}

std::string bus_load_refusal(const CanSettings& s, double rate_hz, const BusLoad& load) {
  // The highest whole rate at which the frames fit in one period (the heartbeats' share of a
  // tick grows as the rate falls), and the bitrate they need at this rate (classic CAN runs at
  // 1 Mbit/s at most).
  double fits = 0.0;
  double too_fast = rate_hz;
  while (too_fast - fits > 1.0) {
    const double mid = std::floor((fits + too_fast) / 2.0);
    (bus_load(s, mid).load <= 1.0 ? fits : too_fast) = mid;
  }
  const double fitting_rate = fits;
  const double needed_bitrate = std::ceil(load.bits_per_tick * rate_hz);
  char text[512];
  std::snprintf(text, sizeof text,
                "the bus cannot carry one tick's frames within one period: %zu node(s) need "
                "%.1f %% of %u bit/s at %.0f Hz (%.2f frames, %.0f bits worst case with stuffing "
                "per tick, %.0f us of each %.0f us period). What would fit: loop.rate_hz at most "
                "%.0f Hz",
                s.nodes.size(), 100.0 * load.load, s.bitrate, rate_hz, load.frames_per_tick,
                load.bits_per_tick, load.bits_per_tick * 1e6 / s.bitrate, 1e6 / rate_hz,
                fitting_rate);
  std::string out = text;
  if (needed_bitrate <= 1e6) {
    std::snprintf(text, sizeof text, "; device.can.bitrate (and the bus's) at least %.0f bit/s",
                  needed_bitrate);
    out += text;
  }
  if (s.nodes.size() > 1) out += "; fewer nodes on this bus";
  return out;
}

std::vector<std::string> bus_load_notes(const CanSettings& s, double rate_hz) {
  const BusLoad load = bus_load(s, rate_hz);
  std::vector<std::string> notes;
  char text[256];
  std::snprintf(text, sizeof text,
                "can bus load: %.1f %% of %u bit/s at %.0f Hz (%.2f frames, %.0f bits worst case "
                "with stuffing per tick, %.0f us of each %.0f us period)",
                100.0 * load.load, s.bitrate, rate_hz, load.frames_per_tick, load.bits_per_tick,
                load.bits_per_tick * 1e6 / s.bitrate, 1e6 / rate_hz);
  notes.emplace_back(text);
  std::string list = "can frames per tick: ";
  for (std::size_t i = 0; i < load.frames.size(); ++i) list += (i ? ", " : "") + load.frames[i];
  notes.push_back(list);
  if (load.load > s.bus_load_warn) {
    std::snprintf(text, sizeof text,
                  "warning: can bus load %.1f %% is above device.can.bus_load_warn %.0f %%%s: "
                  "lower loop.rate_hz or raise the bitrate",
                  100.0 * load.load, 100.0 * s.bus_load_warn,
                  load.load >= 1.0 ? " - the bus cannot carry one tick's frames in one period"
                                   : " - frames will queue and SYNC will jitter");
    notes.emplace_back(text);
  }
  return notes;
}

}  // namespace hapticd::drivers::can
