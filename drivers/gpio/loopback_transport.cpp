#include "drivers/gpio/loopback_transport.h"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

#include "base/clock.h"
#include "base/errno_text.h"
#include "drivers/device.h"

namespace hapticd::drivers::gpio {

JointLevels LoopbackTransport::exchange_levels() {
  std::array<std::uint8_t, wire::kHelloSize> hello{};
  wire::encode_hello(hello);
  if (::send(fd_.get(), hello.data(), hello.size(), MSG_NOSIGNAL) < 0) {
    throw DeviceError(std::string("gpio: the loopback peer is gone: ") + base::errno_text(errno));
  }
  const std::int64_t deadline = base::monotonic_ms() + kHelloTimeoutMs;
  for (;;) {
    const std::int64_t left = deadline - base::monotonic_ms();
    pollfd p{fd_.get(), POLLIN, 0};
    if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) == 0) {
      throw DeviceError("gpio: the loopback peer did not answer within " +
                        std::to_string(kHelloTimeoutMs) + " ms");
    }
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
      throw DeviceError("gpio: the loopback peer closed the connection");
    }
    wire::Levels l;
    if (n > 0 && wire::decode_levels({rx_.data(), static_cast<std::size_t>(n)}, l)) {
      if (l.joint_count != joints_) {
        throw DeviceError("gpio: the loopback peer simulates " + std::to_string(l.joint_count) +
                          " joint(s), the configuration has " + std::to_string(joints_));
      }
      JointLevels levels{};
      for (std::size_t j = 0; j < joints_; ++j) levels[j] = l.of(j);
      return levels;
    }
    // Edges of an earlier session, or garbage: not the answer.
  }
}

JointLevels LoopbackTransport::open(std::span<const OutputState> off) {
  const JointLevels levels = exchange_levels();
  for (SequenceCheck& s : seq_) s.reset();
  for (std::size_t j = 0; j < joints_; ++j) {
    wire::Output stop = off[j];
    stop.duty_ns = 0;
    wire::encode_output(stop, stop_msg_[j]);
  }
  open_ = true;
  for (std::size_t j = 0; j < joints_; ++j) {
    if (const int e = write_output(off[j])) {
      open_ = false;
      throw DeviceError(std::string("gpio: cannot write to the loopback peer: ") +
                        base::errno_text(e));
    }
  }
  return levels;
}

JointLevels LoopbackTransport::read_levels() { return exchange_levels(); }

// RT-safe: called every tick.
EdgeRead LoopbackTransport::read_edges(std::span<Edge> buffer) noexcept {
  EdgeRead r;
  if (!open_) {
    r.error = EBADF;
    return r;
  }
  // Only take a message when a whole one fits: the rest waits in the socket for next tick.
  while (buffer.size() - r.count >= wire::kMaxEdgesPerMessage) {
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n < 0) {
      if (errno != EAGAIN && errno != EINTR) r.error = errno;
      break;
    }
    if (n == 0) {
      r.error = ECONNRESET;  // the peer closed its end: the device is gone
      break;
    }
    const std::span<const std::uint8_t> msg(rx_.data(), static_cast<std::size_t>(n));
    wire::EdgesHeader h;
    if (!wire::decode_edges_header(msg, h)) {
      malformed_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    std::size_t kept = r.count;
    for (std::size_t i = 0; i < h.count; ++i) {
      Edge e;
      // A line, joint or level byte out of range.
      if (!wire::decode_edge(msg, i, e) || e.joint >= joints_) {
        malformed_.fetch_add(1, std::memory_order_relaxed);
        break;
      }
      r.lost[e.joint] += seq_[e.joint].next(e.seqno);
      buffer[kept++] = e;
    }
    r.count = kept;
    if (h.complete_until_ns > r.complete_until_ns) r.complete_until_ns = h.complete_until_ns;
  }
  return r;
}

// RT-safe: called every tick.
int LoopbackTransport::write_output(const OutputState& out) noexcept {
  if (!open_) return EBADF;
  std::array<std::uint8_t, wire::kOutputSize> msg;
  wire::encode_output(out, msg);
  // Never blocks: a peer that stopped reading fills the socket, and that is a failure.
  if (::send(fd_.get(), msg.data(), msg.size(), MSG_DONTWAIT | MSG_NOSIGNAL) < 0) return errno;
  return 0;
}

// Async-signal-safe: send(2) of each joint's prebuilt zero-duty message.
void LoopbackTransport::emergency_stop() noexcept {
  if (!open_) return;
  for (std::size_t j = 0; j < joints_; ++j) {
    [[maybe_unused]] const ssize_t n =
        ::send(fd_.get(), stop_msg_[j].data(), stop_msg_[j].size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  }
}

}  // namespace hapticd::drivers::gpio
