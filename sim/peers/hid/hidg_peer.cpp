#include "sim/peers/hid/hidg_peer.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

#include "base/errno_text.h"
#include "drivers/device.h"

namespace hapticd::sim::hid {
namespace {

// How long an answer may wait for the host to take the previous input report.
constexpr int kSendWaitMs = 50;

}  // namespace

HidgPeer::HidgPeer(const std::string& path, std::unique_ptr<HidFirmware> firmware)
    : FirmwarePeer(std::move(firmware)),
      path_(path),
      fd_(::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC)) {
  if (!fd_) {
    throw DeviceError("hid peer: cannot open the gadget endpoint " + path + ": " +
                      base::errno_text(errno) + " (a USB HID gadget's /dev/hidgN)");
  }
}

void HidgPeer::send(std::span<const std::uint8_t> report) {
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (::write(fd_.get(), report.data(), report.size()) == static_cast<ssize_t>(report.size())) {
      return;
    }
    if (errno != EAGAIN) {
      if (errno == ESHUTDOWN || errno == ENODEV) return;  // the gadget is unbound
      throw std::system_error(errno, std::system_category(), "hid peer: write " + path_);
    }
    // One report in flight at a time: wait for the host's next IN poll to take it.
    pollfd p{fd_.get(), POLLOUT, 0};
    ::poll(&p, 1, kSendWaitMs);
  }
  fw_->count_dropped();
}

void HidgPeer::service() {
  const auto to_host = [this](std::span<const std::uint8_t> r) { send(r); };
  const auto now = std::chrono::steady_clock::now();
  while (true) {
    const ssize_t n = ::read(fd_.get(), rx_.data(), rx_.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == ESHUTDOWN)) break;
    if (n < 0) throw std::system_error(errno, std::system_category(), "hid peer: read " + path_);
    if (n == 0) break;
    fw_->heard_host(now);
    fw_->on_output({rx_.data(), static_cast<std::size_t>(n)}, to_host);
  }
  fw_->check_watchdog(now);
}

bool HidgPeer::inject(PeerFault fault) noexcept {
  return fault == PeerFault::kTransportFault ? false : fw_->inject(fault);
}

}  // namespace hapticd::sim::hid
