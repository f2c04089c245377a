// The bus as a reference device sees it: classic CAN frames read and written as Linux's
// struct can_frame (linux/can.h) on a descriptor - a CAN_RAW socket bound to an interface
// (vcan in the kernel test machine, a real bus anywhere) or one end of a SOCK_SEQPACKET
// socketpair carrying one struct can_frame per message. Written from the kernel's SocketCAN
// documentation (Documentation/networking/can.rst), sharing nothing with drivers/.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace hapticd::reference {

struct Frame {
  std::uint32_t id = 0;  // 11-bit identifier
  std::uint8_t len = 0;
  bool rtr = false;
  std::array<std::uint8_t, 8> data{};

  std::uint16_t u16(int at) const {
    return static_cast<std::uint16_t>(data[at] | data[at + 1] << 8);
  }
  std::uint32_t u32(int at) const {
    return static_cast<std::uint32_t>(data[at]) | static_cast<std::uint32_t>(data[at + 1]) << 8 |
           static_cast<std::uint32_t>(data[at + 2]) << 16 |
           static_cast<std::uint32_t>(data[at + 3]) << 24;
  }
  float f32(int at) const;
  void put_u16(int at, std::uint16_t v) {
    data[at] = static_cast<std::uint8_t>(v);
    data[at + 1] = static_cast<std::uint8_t>(v >> 8);
  }
  void put_u32(int at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) data[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  void put_f32(int at, float v);
};

inline Frame make_frame(std::uint32_t id, std::uint8_t len) {
  Frame f;
  f.id = id;
  f.len = len;
  return f;
}

// One end of the bus. Owns its descriptor.
class CanPort {
 public:
  // CAN_RAW on `interface`, every frame received (a device sees the whole bus).
  static CanPort open(const std::string& interface);
  // Adopts one end of a SOCK_SEQPACKET socketpair.
  static CanPort adopt(int fd) { return CanPort(fd); }
  CanPort(CanPort&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  CanPort& operator=(CanPort&&) = delete;
  ~CanPort();

  // Non-blocking: nothing when none waits (or the message is not a classic frame).
  std::optional<Frame> receive();
  // False when the other end is gone or the queue is full.
  bool send(const Frame& f);
  int fd() const { return fd_; }

 private:
  explicit CanPort(int fd) : fd_(fd) {}
  int fd_ = -1;
};

// CLOCK_MONOTONIC in ns.
std::int64_t monotonic_ns();

}  // namespace hapticd::reference
