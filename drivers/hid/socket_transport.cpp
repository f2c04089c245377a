#include "drivers/hid/socket_transport.h"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

#include "base/errno_text.h"
#include "drivers/device.h"

namespace hapticd::drivers::hid {
std::vector<std::uint8_t> SocketTransport::transact(const std::vector<std::uint8_t>& request,
                                                    FrameType expected, const char* what) {
  if (::send(fd_.get(), request.data(), request.size(), MSG_DONTWAIT | MSG_NOSIGNAL) < 0) {
    throw DeviceError(std::string("hid: ") + what + ": " + base::errno_text(errno));
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout_;
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd p{fd_.get(), POLLIN, 0};
    if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) == 0) {
      throw DeviceError(std::string("hid: ") + what + ": the device did not answer within " +
                        std::to_string(timeout_.count()) + " ms");
    }
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n == 0) throw DeviceError(std::string("hid: ") + what + ": the device is gone");
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      throw DeviceError(std::string("hid: ") + what + ": " + base::errno_text(errno));
    }
    const auto f = parse_frame({rx_.data(), static_cast<std::size_t>(n)});
    if (!f || f->type != expected) continue;  // input reports meanwhile, a late reply
    if (f->payload.empty()) throw DeviceError(std::string("hid: ") + what + ": empty reply");
    if (f->payload[0] != 0) {
      throw DeviceError(std::string("hid: ") + what + ": the device refused (" +
                        base::errno_text(f->payload[0]) + ")");
    }
    return {f->payload.begin() + 1, f->payload.end()};
  }
}

std::vector<std::uint8_t> SocketTransport::report_descriptor() {
  return transact(frame(FrameType::kGetDescriptor, {}), FrameType::kDescriptorReply,
                  "reading the report descriptor");
}

void SocketTransport::set_feature(std::span<const std::uint8_t> report) {
  const std::string what = "feature report " + std::to_string(report.empty() ? 0 : report[0]);
  transact(frame(FrameType::kSetFeature, report), FrameType::kSetFeatureReply, what.c_str());
}

std::vector<std::uint8_t> SocketTransport::get_feature(std::uint8_t id, std::size_t length) {
  const std::string what = "reading feature report " + std::to_string(id);
  std::vector<std::uint8_t> r = transact(
      get_feature_request(id, static_cast<std::uint16_t>(std::min<std::size_t>(length, 0xFFFF))),
      FrameType::kGetFeatureReply, what.c_str());
  if (r.size() > length) r.resize(length);
  return r;
}

IoResult SocketTransport::read(std::span<std::uint8_t> buffer) noexcept {
  while (true) {
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT | MSG_TRUNC);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return {TransportIo::kEmpty, 0, 0};
      if (errno == EINTR) continue;
      return {TransportIo::kError, 0, errno};
    }
    if (n == 0) return {TransportIo::kError, 0, ENODEV};  // the peer closed: the device is gone
    const auto size = static_cast<std::size_t>(n);
    if (size > rx_.size()) return {TransportIo::kError, 0, EMSGSIZE};
    const auto f = parse_frame({rx_.data(), size});
    if (!f || f->type != FrameType::kInputReport) continue;  // a late reply: not a sample
    if (f->payload.size() > buffer.size()) return {TransportIo::kError, 0, EMSGSIZE};
    std::memcpy(buffer.data(), f->payload.data(), f->payload.size());
    return {TransportIo::kOk, f->payload.size(), 0};
  }
}

IoResult SocketTransport::write(std::span<const std::uint8_t> report) noexcept {
  if (report.size() + 1 > tx_.size()) return {TransportIo::kError, 0, EMSGSIZE};
  const std::size_t n = write_frame(FrameType::kOutputReport, report, tx_);
  if (::send(fd_.get(), tx_.data(), n, MSG_DONTWAIT | MSG_NOSIGNAL) >= 0) {
    return {TransportIo::kOk, n, 0};
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)
    return {TransportIo::kEmpty, 0, errno};
  return {TransportIo::kError, 0, errno};
}

void SocketTransport::set_safe_reports(std::vector<std::vector<std::uint8_t>> reports) {
  safe_.clear();
  for (const auto& r : reports) safe_.push_back(frame(FrameType::kOutputReport, r));
}

void SocketTransport::write_safe() noexcept { emergency(); }

void SocketTransport::emergency() noexcept {
  for (const auto& m : safe_) {
    [[maybe_unused]] const ssize_t n =
        ::send(fd_.get(), m.data(), m.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  }
}

}  // namespace hapticd::drivers::hid
