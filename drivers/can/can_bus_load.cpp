#include "drivers/can/can_bus_load.h"

#include <algorithm>
#include <cstdio>

namespace hapticd::drivers::can {
namespace {

struct Cyclic {
  const char* name;
  int bytes;
  double per_tick;  // 1 for every tick, less for a heartbeat
};

void add(BusLoad& load, const Cyclic& c) {
  load.frames_per_tick += c.per_tick;
  load.bits_per_tick += c.per_tick * worst_case_frame_bits(c.bytes);
  char text[96];
  if (c.per_tick == 1.0) {
    std::snprintf(text, sizeof text, "%s (%d byte%s)", c.name, c.bytes, c.bytes == 1 ? "" : "s");
  } else {
    std::snprintf(text, sizeof text, "%s (%d byte%s, every %.0f ticks)", c.name, c.bytes,
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
  if (s.profile == Profile::kCia402) {
    add(load, {"SYNC", 0, 1.0});
    add(load, {"RPDO1 controlword + target torque", 4, 1.0});
    add(load, {"TPDO1 statusword + position", 6, 1.0});
    if (s.cia402.map_velocity) add(load, {"TPDO2 velocity", 4, 1.0});
    add(load, {"drive heartbeat", 1, every(s.cia402.heartbeat_producer_ms)});
    if (s.cia402.master_heartbeat_ms > 0) {
      add(load, {"hapticd heartbeat", 1, every(s.cia402.master_heartbeat_ms)});
    }
  } else {
    add(load, {"Set_Input_Torque", 4, 1.0});
    if (s.odrive.position_source == PositionSource::kRequest) {
      add(load, {"Get_Encoder_Estimates request (RTR)", 0, 1.0});
      add(load, {"Get_Encoder_Estimates", 8, 1.0});
    } else {
      add(load, {"Get_Encoder_Estimates (cyclic)", 8, every(s.odrive.cyclic_period_ms)});
    }
    add(load, {"Heartbeat", 8, every(s.odrive.heartbeat_period_ms)});
  }
  load.load = load.bits_per_tick * rate_hz / s.bitrate;
  return load;
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
