// The host's end of the simulated Falcon's loopback socketpair (sim/peers/falcon/falcon_peer.h),
// written for the tests from the wire the codec's LoopbackTag describes: an FtdiLink, so the
// driver's firmware loader runs against the peer unchanged, plus raw helpers to send one message
// and collect what came back. With `pump` set, every send runs the peer's service() at once
// (one thread, deterministic); without, a PeerRunner serves the peer on its own thread.
#pragma once

#include <poll.h>
#include <sys/socket.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <string>
#include <vector>

#include "drivers/falcon/ftdi_link.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/loopback_peer.h"

namespace hapticd::sim::falcon::testing {

namespace df = drivers::falcon;

class SocketFalconHost final : public df::FtdiLink {
 public:
  SocketFalconHost(io::UniqueFd fd, LoopbackPeer* pump) : fd_(std::move(fd)), pump_(pump) {}

  bool control(const df::FtdiRequest& r, std::string& error) override {
    const unsigned char m[4] = {df::kTagControl, r.request, static_cast<unsigned char>(r.value),
                                static_cast<unsigned char>(r.value >> 8)};
    return send_message(m, error);
  }
  bool write(std::span<const unsigned char> data, int, std::string& error) override {
    std::vector<unsigned char> m{df::kTagBulkOut};
    m.insert(m.end(), data.begin(), data.end());
    return send_message(m, error);
  }
  int read(std::span<unsigned char> buffer, int timeout_ms, std::string& error) override {
    pollfd p{fd_.get(), POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return 0;
    std::array<unsigned char, 1 + 4 * df::kUsbPacketBytes> m{};
    const ssize_t n = ::recv(fd_.get(), m.data(), m.size(), MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN)) {
      error = n == 0 ? "the device is gone (end of file)" : std::strerror(errno);
      return -1;
    }
    if (n < 0) return 0;
    if (m[0] != df::kTagBulkIn) {
      error = "not a bulk IN message";
      return -1;
    }
    ++transfers_;
    const auto size = static_cast<std::size_t>(n - 1);
    if (size > buffer.size()) {
      error = "a transfer larger than the buffer";
      return -1;
    }
    std::memcpy(buffer.data(), m.data() + 1, size);
    last_transfer_.assign(m.begin() + 1, m.begin() + n);
    return static_cast<int>(size);
  }

  // Raw: one request, one OUT transfer.
  bool control(std::uint8_t request, std::uint16_t value) {
    std::string e;
    return control(df::FtdiRequest{request, value, ""}, e);
  }
  bool out(std::span<const unsigned char> data) {
    std::string e;
    return write(data, 0, e);
  }
  bool requests(std::span<const df::FtdiRequest> rs) {
    for (const df::FtdiRequest& r : rs) {
      std::string e;
      if (!control(r, e)) return false;
    }
    return true;
  }
  // Every data byte waiting (modem status dropped), within `timeout_ms` for the first.
  std::vector<unsigned char> data(int timeout_ms = 0) {
    std::vector<unsigned char> d;
    std::array<unsigned char, 4 * df::kUsbPacketBytes> b{};
    std::string e;
    for (int got = read(b, timeout_ms, e); got > 0; got = read(b, 0, e)) {
      for (int k = 0; k < got; ++k) {
        if (static_cast<std::size_t>(k) % df::kUsbPacketBytes >= df::kModemStatusBytes) {
          d.push_back(b[static_cast<std::size_t>(k)]);
        }
      }
    }
    return d;
  }
  int transfers() const noexcept { return transfers_; }
  const std::vector<unsigned char>& last_transfer() const noexcept { return last_transfer_; }
  int fd() const noexcept { return fd_.get(); }

 private:
  bool send_message(std::span<const unsigned char> m, std::string& error) {
    if (::send(fd_.get(), m.data(), m.size(), MSG_NOSIGNAL) < 0) {
      error = std::strerror(errno);
      return false;
    }
    if (pump_ != nullptr) pump_->service();
    return true;
  }

  io::UniqueFd fd_;
  LoopbackPeer* pump_;
  int transfers_ = 0;
  std::vector<unsigned char> last_transfer_;
};

}  // namespace hapticd::sim::falcon::testing
