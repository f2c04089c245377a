#include "drivers/can/can_socket.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "base/clock.h"
#include "drivers/device.h"

namespace hapticd::drivers::can {
namespace {

static_assert(sizeof(WireFrame) == sizeof(can_frame), "WireFrame is struct can_frame");
static_assert(alignof(WireFrame) >= alignof(can_frame));

[[noreturn]] void fail(const std::string& what, int error) {
  throw DeviceError("can: " + what + ": " + std::strerror(error));
}

BusEvent decode_error_frame(const can_frame& cf) noexcept {
  BusEvent e;
  const canid_t cls = cf.can_id & CAN_ERR_MASK;
  e.tx_timeout = (cls & CAN_ERR_TX_TIMEOUT) != 0;
  e.lost_arbitration = (cls & CAN_ERR_LOSTARB) != 0;
  e.protocol_violation = (cls & CAN_ERR_PROT) != 0;
  e.transceiver = (cls & CAN_ERR_TRX) != 0;
  e.no_ack = (cls & CAN_ERR_ACK) != 0;
  e.bus_off = (cls & CAN_ERR_BUSOFF) != 0;
  e.bus_error = (cls & CAN_ERR_BUSERROR) != 0;
  e.restarted = (cls & CAN_ERR_RESTARTED) != 0;
  if ((cls & CAN_ERR_CRTL) != 0 && cf.len >= 2) {
    const std::uint8_t c = cf.data[1];
    e.rx_overflow = (c & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) != 0;
    e.error_warning = (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0;
    e.error_passive = (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0;
  }
  return e;
}

can_frame encode_error_frame(const BusEvent& e) noexcept {
  can_frame cf{};
  canid_t cls = 0;
  if (e.tx_timeout) cls |= CAN_ERR_TX_TIMEOUT;
  if (e.lost_arbitration) cls |= CAN_ERR_LOSTARB;
  if (e.protocol_violation) cls |= CAN_ERR_PROT;
  if (e.transceiver) cls |= CAN_ERR_TRX;
  if (e.no_ack) cls |= CAN_ERR_ACK;
  if (e.bus_off) cls |= CAN_ERR_BUSOFF;
  if (e.bus_error) cls |= CAN_ERR_BUSERROR;
  if (e.restarted) cls |= CAN_ERR_RESTARTED;
  if (e.rx_overflow || e.error_warning || e.error_passive) {
    cls |= CAN_ERR_CRTL;
    cf.data[1] = static_cast<__u8>((e.rx_overflow ? CAN_ERR_CRTL_RX_OVERFLOW : 0) |
                                   (e.error_warning ? CAN_ERR_CRTL_RX_WARNING : 0) |
                                   (e.error_passive ? CAN_ERR_CRTL_RX_PASSIVE : 0));
  }
  cf.can_id = CAN_ERR_FLAG | cls;
  cf.len = CAN_ERR_DLC;
  return cf;
}

std::int64_t to_ns(const timespec& ts) noexcept {
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// SO_TIMESTAMPNS stamps CLOCK_REALTIME; the loop wants CLOCK_MONOTONIC. The offset between the
// two is read now (vDSO, no system call), so a step of the wall clock moves at most this frame;
// the monotonic read is bracketed by two realtime reads and taken again when the bracket is
// wide (the thread was preempted between them), so the offset is good to a few microseconds.
// (CLOCK_REALTIME is read here only: base/clock.h is the monotonic clock.)
std::int64_t realtime_to_monotonic(std::int64_t realtime_ns) noexcept {
  std::int64_t offset = 0;
  for (int attempt = 0; attempt < 4; ++attempt) {
    timespec r1;
    timespec r2;
    clock_gettime(CLOCK_REALTIME, &r1);
    const std::int64_t mono = base::monotonic_ns();
    clock_gettime(CLOCK_REALTIME, &r2);
    offset = (to_ns(r1) + (to_ns(r2) - to_ns(r1)) / 2) - mono;
    if (to_ns(r2) - to_ns(r1) < 20'000) break;
  }
  return realtime_ns - offset;
}

void enable_timestamps(int fd, const std::string& what) {
  const int on = 1;
  if (setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) != 0) {
    fail(what + ": SO_TIMESTAMPNS", errno);
  }
}

}  // namespace

CanSocket CanSocket::open_interface(const std::string& interface, std::span<const IdFilter> filters,
                                    bool error_frames) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    throw DeviceError("can: '" + interface + "' is not a network interface name");
  }
  io::UniqueFd fd(socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!fd) fail("socket(PF_CAN, CAN_RAW) (is the can_raw module loaded?)", errno);
  const unsigned index = if_nametoindex(interface.c_str());
  if (index == 0) fail("interface " + interface, errno);
  std::vector<can_filter> kernel_filters;
  for (const IdFilter& f : filters) {
    // Only standard data and remote frames of these ids: extended frames never match.
    kernel_filters.push_back({f.id, f.mask | CAN_EFF_FLAG});
  }
  if (setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_FILTER, kernel_filters.data(),
                 static_cast<socklen_t>(kernel_filters.size() * sizeof(can_filter))) != 0) {
    fail(interface + ": CAN_RAW_FILTER", errno);
  }
  const can_err_mask_t errors = error_frames ? CAN_ERR_MASK : 0;
  if (setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0) {
    fail(interface + ": CAN_RAW_ERR_FILTER", errno);
  }
  enable_timestamps(fd.get(), interface);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (bind(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    fail("bind to " + interface, errno);
  }
  return CanSocket(std::move(fd), interface);
}

CanSocket CanSocket::adopt(io::UniqueFd fd, std::string description) {
  enable_timestamps(fd.get(), description);
  return CanSocket(std::move(fd), std::move(description));
}

WireFrame CanSocket::to_wire(const CanFrame& frame) noexcept {
  can_frame cf{};
  cf.can_id = (frame.id & (frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK)) |
              (frame.extended ? CAN_EFF_FLAG : 0) | (frame.rtr ? CAN_RTR_FLAG : 0);
  cf.len = frame.len > CAN_MAX_DLEN ? CAN_MAX_DLEN : frame.len;
  if (!frame.rtr) std::memcpy(cf.data, frame.data.data(), cf.len);
  WireFrame w;
  std::memcpy(w.bytes, &cf, sizeof cf);
  return w;
}

void CanSocket::write_wire(int fd, std::span<const WireFrame> frames) noexcept {
  for (const WireFrame& w : frames) {
    [[maybe_unused]] const ssize_t n = ::write(fd, w.bytes, sizeof w.bytes);
  }
}

CanSocket::Io CanSocket::send(const CanFrame& frame, int& error) noexcept {
  const WireFrame w = to_wire(frame);
  const ssize_t n = ::send(fd_.get(), w.bytes, sizeof w.bytes, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n == static_cast<ssize_t>(sizeof w.bytes)) return Io::kDone;
  error = n < 0 ? errno : EIO;
  // ENOBUFS: the interface's queue is full; EAGAIN: the socket's send buffer is. Either way
  // the frame did not go, and waiting for room is not the RT thread's to do.
  return n < 0 && (errno == ENOBUFS || errno == EAGAIN) ? Io::kEmpty : Io::kFailed;
}

CanSocket::Io CanSocket::send_event(const BusEvent& event, int& error) noexcept {
  const can_frame cf = encode_error_frame(event);
  const ssize_t n = ::send(fd_.get(), &cf, sizeof cf, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n == static_cast<ssize_t>(sizeof cf)) return Io::kDone;
  error = n < 0 ? errno : EIO;
  return Io::kFailed;
}

CanSocket::Io CanSocket::receive(Received& out, int& error) noexcept {
  can_frame cf{};
  iovec iov{&cf, sizeof cf};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_.get(), &msg, MSG_DONTWAIT);
  if (n < 0) {
    if (errno == EAGAIN || errno == EINTR) return Io::kEmpty;
    error = errno;
    return Io::kFailed;
  }
  if (n == 0) {  // a socketpair's other end closed: the "device" is gone
    error = 0;
    return Io::kFailed;
  }
  if (n != static_cast<ssize_t>(sizeof cf) || (msg.msg_flags & MSG_TRUNC) != 0 ||
      cf.len > CAN_MAX_DLEN) {
    return Io::kMalformed;
  }
  out.time_ns = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts;
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      out.time_ns = realtime_to_monotonic(to_ns(ts));
    }
  }
  const std::int64_t now = base::monotonic_ns();
  // Never in the future (a wall-clock step between the stamp and now would put it there).
  if (out.time_ns == 0 || out.time_ns > now) out.time_ns = now;
  out.is_event = (cf.can_id & CAN_ERR_FLAG) != 0;
  if (out.is_event) {
    out.event = decode_error_frame(cf);
    return Io::kDone;
  }
  out.frame.extended = (cf.can_id & CAN_EFF_FLAG) != 0;
  out.frame.rtr = (cf.can_id & CAN_RTR_FLAG) != 0;
  out.frame.id = cf.can_id & (out.frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out.frame.len = cf.len;
  out.frame.data = {};
  if (!out.frame.rtr) std::memcpy(out.frame.data.data(), cf.data, cf.len);
  return Io::kDone;
}

bool CanSocket::wait_readable(int timeout_ms) const {
  pollfd p{fd_.get(), POLLIN, 0};
  while (true) {
    const int r = poll(&p, 1, timeout_ms);
    if (r < 0 && errno == EINTR) continue;
    return r > 0;
  }
}

}  // namespace hapticd::drivers::can
