#include "reference/can/can_wire.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace hapticd::reference {

float Frame::f32(int at) const {
  const std::uint32_t bits = u32(at);
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

void Frame::put_f32(int at, float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  put_u32(at, bits);
}

std::int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

CanPort CanPort::open(const std::string& interface) {
  const int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0)
    throw std::runtime_error("reference device: socket(CAN_RAW): " + std::string(strerror(errno)));
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(if_nametoindex(interface.c_str()));
  if (addr.can_ifindex == 0 || bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const int e = errno;
    ::close(fd);
    throw std::runtime_error("reference device: bind to " + interface + ": " + strerror(e));
  }
  return CanPort(fd);
}

CanPort::~CanPort() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<Frame> CanPort::receive() {
  can_frame cf{};
  const ssize_t n = recv(fd_, &cf, sizeof cf, MSG_DONTWAIT);
  if (n != static_cast<ssize_t>(sizeof cf)) return std::nullopt;
  if ((cf.can_id & (CAN_EFF_FLAG | CAN_ERR_FLAG)) != 0) return std::nullopt;
  Frame f;
  f.id = cf.can_id & CAN_SFF_MASK;
  f.rtr = (cf.can_id & CAN_RTR_FLAG) != 0;
  f.len = cf.len > 8 ? 8 : cf.len;
  std::memcpy(f.data.data(), cf.data, 8);
  return f;
}

bool CanPort::send(const Frame& f) {
  can_frame cf{};
  cf.can_id = (f.id & CAN_SFF_MASK) | (f.rtr ? CAN_RTR_FLAG : 0);
  cf.len = f.len;
  if (!f.rtr) std::memcpy(cf.data, f.data.data(), 8);
  return ::send(fd_, &cf, sizeof cf, MSG_DONTWAIT | MSG_NOSIGNAL) ==
         static_cast<ssize_t>(sizeof cf);
}

}  // namespace hapticd::reference
