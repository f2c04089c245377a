// A classic CAN frame and the bus events SocketCAN reports, as the pure codecs see them: no OS
// header here (can_socket.h is the one place that knows struct can_frame), so the CiA 301/402
// and ODrive codecs, the devices' protocol logic and the simulated drives are plain functions
// of bytes that tests and fuzzers can call directly. Little-endian helpers too: CANopen and
// ODrive CAN Simple are both little-endian on the wire.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>

namespace hapticd::drivers::can {

inline constexpr std::uint32_t kSffMask = 0x7FF;  // an 11-bit identifier

struct CanFrame {
  std::uint32_t id = 0;  // 11-bit (or 29-bit with `extended`) identifier, no flag bits
  std::uint8_t len = 0;  // data length code, 0..8
  bool rtr = false;      // remote transmission request (no data, len is the requested size)
  bool extended = false;
  std::array<std::uint8_t, 8> data{};
};

// What an error frame of the controller said (SocketCAN's CAN_ERR_* classes, decoded by
// can_socket.cpp). Several can be set at once.
struct BusEvent {
  bool bus_off = false;           // the controller left the bus: nothing goes out any more
  bool error_passive = false;     // TX or RX error counter above 127
  bool error_warning = false;     // TX or RX error counter above 95
  bool rx_overflow = false;       // frames lost in the controller or its driver
  bool tx_timeout = false;        // a frame was not acknowledged in time
  bool lost_arbitration = false;  // another node won arbitration (normal under load)
  bool protocol_violation = false;
  bool no_ack = false;       // nobody acknowledged: the drive is off or unplugged
  bool bus_error = false;    // bit, stuff, form or CRC errors
  bool restarted = false;    // the controller came back after bus-off
  bool transceiver = false;  // a transceiver status change (CAN_H/CAN_L wiring)
};

// Little-endian field access on a frame's data; offsets are the caller's to keep in range.
inline std::uint16_t get_u16(const CanFrame& f, int at) noexcept {
  return static_cast<std::uint16_t>(f.data[at] | (f.data[at + 1] << 8));
}
inline std::uint32_t get_u32(const CanFrame& f, int at) noexcept {
  return static_cast<std::uint32_t>(f.data[at]) |
         (static_cast<std::uint32_t>(f.data[at + 1]) << 8) |
         (static_cast<std::uint32_t>(f.data[at + 2]) << 16) |
         (static_cast<std::uint32_t>(f.data[at + 3]) << 24);
}
inline float get_f32(const CanFrame& f, int at) noexcept {
  const std::uint32_t bits = get_u32(f, at);
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}
inline void put_u16(CanFrame& f, int at, std::uint16_t v) noexcept {
  f.data[at] = static_cast<std::uint8_t>(v);
  f.data[at + 1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_u32(CanFrame& f, int at, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) f.data[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void put_f32(CanFrame& f, int at, float v) noexcept {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  put_u32(f, at, bits);
}

inline CanFrame make_frame(std::uint32_t id, std::uint8_t len) noexcept {
  CanFrame f;
  f.id = id;
  f.len = len;
  return f;
}

}  // namespace hapticd::drivers::can
