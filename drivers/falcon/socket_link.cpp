#include "drivers/falcon/socket_link.h"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "base/clock.h"
#include "base/errno_text.h"

namespace hapticd::drivers::falcon {
namespace {

constexpr int kFlags = MSG_DONTWAIT | MSG_NOSIGNAL;

bool gone(int e) noexcept { return e == EPIPE || e == ECONNRESET || e == ENOTCONN; }

// RT- and async-signal-safe: one command packet as a bulk OUT message; send(2)'s result.
ssize_t send_packet(int fd, const Packet& p) noexcept {
  std::array<unsigned char, 1 + kPacketBytes> m{};
  m[0] = kTagBulkOut;
  std::memcpy(m.data() + 1, p.data(), p.size());
  return ::send(fd, m.data(), m.size(), kFlags);
}

}  // namespace

bool SocketLink::send_message(unsigned char tag, std::span<const unsigned char> data,
                              std::string& error) {
  std::array<unsigned char, 1 + kLoadChunkBytes> m{};
  if (data.size() + 1 > m.size()) {
    error = "a transfer of " + std::to_string(data.size()) + " bytes (at most 128)";
    return false;
  }
  m[0] = tag;
  if (!data.empty()) std::memcpy(m.data() + 1, data.data(), data.size());
  if (::send(fd_.get(), m.data(), data.size() + 1, kFlags) < 0) {
    error_ = errno;
    error = gone(errno) ? "the device is gone" : base::errno_text(errno);
    return false;
  }
  return true;
}

bool SocketLink::control(const FtdiRequest& r, std::string& error) {
  const unsigned char d[3] = {r.request, static_cast<unsigned char>(r.value & 0xFF),
                              static_cast<unsigned char>(r.value >> 8)};
  return send_message(kTagControl, d, error);
}

bool SocketLink::write(std::span<const unsigned char> data, int, std::string& error) {
  return send_message(kTagBulkOut, data, error);
}

int SocketLink::read(std::span<unsigned char> buffer, int timeout_ms, std::string& error) {
  pollfd p{fd_.get(), POLLIN, 0};
  const int ready = ::poll(&p, 1, std::max(0, timeout_ms));
  if (ready == 0) return 0;
  const ssize_t n = ready < 0 ? -1 : ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
  if (n == 0) {
    error = "the device is gone";
    return -1;
  }
  if (n < 0) {
    if (errno == EAGAIN || errno == EINTR) return 0;
    error_ = errno;
    error = gone(errno) ? "the device is gone" : base::errno_text(errno);
    return -1;
  }
  if (rx_[0] != kTagBulkIn) return 0;  // nothing else comes this way
  const auto size = std::min(static_cast<std::size_t>(n) - 1, buffer.size());
  std::memcpy(buffer.data(), rx_.data() + 1, size);
  return static_cast<int>(size);
}

TransportIo SocketLink::send(const Packet& p) noexcept {
  if (send_packet(fd_.get(), p) >= 0) return TransportIo::kOk;
  if (errno == EAGAIN) return TransportIo::kEmpty;
  error_ = gone(errno) ? ENODEV : errno;
  return TransportIo::kError;
}

TransportIo SocketLink::receive(PacketStream& stream) noexcept {
  for (;;) {
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n > 0) {
      if (rx_[0] == kTagBulkIn) {
        stream.feed_transfer({rx_.data() + 1, static_cast<std::size_t>(n) - 1});
        received_ns_ = base::monotonic_ns();
      }
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return TransportIo::kOk;
    error_ = n == 0 || gone(errno) ? ENODEV : errno;  // end of file: the peer closed, unplugged
    return TransportIo::kError;
  }
}

void SocketLink::emergency(const Packet& p) noexcept {
  [[maybe_unused]] const ssize_t n = send_packet(fd_.get(), p);
}

}  // namespace hapticd::drivers::falcon
