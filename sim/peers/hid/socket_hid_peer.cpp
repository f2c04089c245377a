#include "sim/peers/hid/socket_hid_peer.h"

#include <sys/socket.h>

#include <cerrno>
#include <system_error>

namespace hapticd::sim::hid {

using drivers::hid::FrameType;

void SocketHidPeer::send(const std::vector<std::uint8_t>& message) {
  if (::send(fd_.get(), message.data(), message.size(), MSG_DONTWAIT | MSG_NOSIGNAL) < 0 &&
      errno != EPIPE && errno != ECONNRESET) {
    // A full socket means the driver stopped reading: the answer is lost, as on a bus.
    if (errno == EAGAIN) {
      fw_->count_dropped();
      return;
    }
    throw std::system_error(errno, std::system_category(), "hid peer: send");
  }
}

void SocketHidPeer::handle(const drivers::hid::FrameView& f) {
  const auto to_host = [this](std::span<const std::uint8_t> report) {
    send(drivers::hid::frame(FrameType::kInputReport, report));
  };
  switch (f.type) {
    case FrameType::kOutputReport:
      fw_->on_output(f.payload, to_host);
      return;
    case FrameType::kSetFeature: {
      const int status = fw_->on_set_feature(f.payload, to_host);
      send(drivers::hid::reply(FrameType::kSetFeatureReply, static_cast<std::uint8_t>(status), {}));
      return;
    }
    case FrameType::kGetFeature: {
      std::vector<std::uint8_t> report;
      const int status = f.payload.empty() ? EINVAL : fw_->on_get_feature(f.payload[0], report);
      if (f.payload.size() >= 3) {
        const std::size_t max = f.payload[1] | (std::size_t{f.payload[2]} << 8);
        if (report.size() > max) report.resize(max);
      }
      send(drivers::hid::reply(FrameType::kGetFeatureReply, static_cast<std::uint8_t>(status),
                               report));
      return;
    }
    case FrameType::kGetDescriptor:
      send(drivers::hid::reply(FrameType::kDescriptorReply, 0, fw_->descriptor()));
      return;
    default:
      return;  // a device never receives the host's own message types
  }
}

void SocketHidPeer::service() {
  if (vanished_.load()) {
    fw_->lose_host();
    // What the driver sent before the device vanished is lost with it, but taken off the
    // socket: the runner stops at the hang-up, and wait_idle() must not see it still unread.
    while (::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT) > 0) {
    }
    return;
  }
  while (true) {
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {  // the driver closed its end, or the pair broke: the host is gone
      fw_->lose_host();
      return;
    }
    if (const auto f = drivers::hid::parse_frame({rx_.data(), static_cast<std::size_t>(n)})) {
      handle(*f);
    }
  }
}

bool SocketHidPeer::inject(PeerFault fault) noexcept {
  if (fault != PeerFault::kTransportFault) return fw_->inject(fault);
  fw_->vanish();
  ::shutdown(fd_.get(), SHUT_RDWR);  // the driver's next call sees the device gone
  vanished_.store(true);             // after it: nothing arrives once service() drains
  return true;
}

}  // namespace hapticd::sim::hid
