#include "sim/peers/falcon/falcon_peer.h"

#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <stdexcept>
#include <system_error>

namespace hapticd::sim::falcon {
namespace {

namespace df = drivers::falcon;

// The modem status an idle FT232 leads each USB packet with (CTS, DSR; TX empty).
constexpr unsigned char kModemStatus[df::kModemStatusBytes] = {0x31, 0x60};
constexpr std::size_t kDataPerUsbPacket = df::kUsbPacketBytes - df::kModemStatusBytes;
// One USB packet per IN message: any host buffer of a USB packet takes it whole (a larger
// SOCK_SEQPACKET message would be cut by a smaller one), and a tick's state packet fits.
constexpr std::size_t kUsbPacketsPerTransfer = 1;

}  // namespace

FalconPeer::FalconPeer(const config::Config& cfg, io::UniqueFd fd, FalconPeerOptions options)
    : axis_(cfg.device, cfg.loop.sample_period_s()),
      chip_(options.fail_first_load),
      firmware_(cfg.device, cfg.loop.sample_period_s(), options.homing_packets),
      fd_(std::move(fd)) {
  if (firmware_.mechanism().joints() != 3) {
    throw std::invalid_argument(
        "the simulated Falcon needs a device.kinematics of three joints (delta)");
  }
}

void FalconPeer::service() {
  std::array<unsigned char, 1024> rx{};
  for (;;) {
    const ssize_t n = ::recv(fd_.get(), rx.data(), rx.size(), MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR || shut_) break;
      if (errno == ECONNRESET) return;  // the driver closed its end
      throw std::system_error(errno, std::system_category(), "falcon peer: recv");
    }
    if (n == 0) return;  // the driver closed its end
    handle({rx.data(), static_cast<std::size_t>(n)});
  }
  flush();
}

bool FalconPeer::inject(PeerFault f) noexcept {
  if (!faults_.inject(f)) return false;
  if (f == PeerFault::kTransportFault) {
    // The socket first, as the serial peer does: a flag set before it could leave the peer
    // silent on an open socket, and the host would see stale data, not the unplug.
    ::shutdown(fd_.get(), SHUT_RDWR);
    shut_ = true;
    felt_.vanish();
  }
  return true;
}

void FalconPeer::handle(std::span<const unsigned char> message) {
  if (shut_) return;
  if (message.size() == 4 && message[0] == df::kTagControl) {
    control(message[1], static_cast<std::uint16_t>(message[2] | (message[3] << 8)));
  } else if (!message.empty() && message[0] == df::kTagBulkOut) {
    bulk_out(message.subspan(1));
  } else {
    ++bad_messages_;  // not the loopback's wire: counted, ignored
  }
  flush();
}

void FalconPeer::control(std::uint8_t request, std::uint16_t value) {
  switch (chip_.control(request, value)) {
    case ChipEffect::kNone:
      return;
    case ChipEffect::kPurgeToHost:
      pending_.clear();  // what the socket already holds is the host's link's to drop
      return;
    case ChipEffect::kPurgeFromHost:
      firmware_.drop_input();
      return;
    case ChipEffect::kReset:
      firmware_.stop();
      pending_.clear();
      running_ = false;
      ++resets_;
      publish();
      return;
    case ChipEffect::kFirmwareStarts:
      firmware_.start();
      running_ = true;
      loads_ = chip_.loads_completed();
      publish();
      return;
  }
}

void FalconPeer::bulk_out(std::span<const unsigned char> data) {
  if (chip_.mode() != McuMode::kFirmware) {
    chip_.bulk_out(data, pending_);
    return;
  }
  answers_.clear();
  firmware_.receive(data, answers_);
  publish();
  if (faults_.active(PeerFault::kStopAnswering)) return;  // hung: taken, never answered
  for (df::Packet& p : answers_) {
    if (corrupt_next_.exchange(false)) p[5] = '0';  // out of 'A'..'P': the host's kBadNibble
    pending_.insert(pending_.end(), p.begin(), p.end());
  }
  answered_ += answers_.size();
}

void FalconPeer::publish() noexcept {
  felt_.publish(firmware_.felt_torque(), firmware_.amplifier_on());
  leds_ = firmware_.leds();
  homed_ = firmware_.homed();
  taken_ = firmware_.packets_taken();
}

void FalconPeer::flush() {
  // A hung device: the motors keep their last torque and nothing comes back.
  if (faults_.active(PeerFault::kStopAnswering)) pending_.clear();
  std::array<unsigned char, 1 + kUsbPacketsPerTransfer * df::kUsbPacketBytes> tx{};
  std::size_t sent = 0;
  while (sent < pending_.size() && !shut_) {
    std::size_t n = 0, taken = 0;
    tx[n++] = df::kTagBulkIn;
    for (std::size_t usb = 0; usb < kUsbPacketsPerTransfer && sent + taken < pending_.size();
         ++usb) {
      const std::size_t data = std::min(kDataPerUsbPacket, pending_.size() - sent - taken);
      const auto from = pending_.begin() + static_cast<long>(sent + taken);
      std::copy_n(kModemStatus, df::kModemStatusBytes, tx.begin() + static_cast<long>(n));
      std::copy_n(from, data, tx.begin() + static_cast<long>(n + df::kModemStatusBytes));
      n += df::kModemStatusBytes + data;
      taken += data;
    }
    if (::send(fd_.get(), tx.data(), n, MSG_DONTWAIT | MSG_NOSIGNAL) < 0) {
      if (errno == EAGAIN) break;  // the host is behind: the chip's FIFO keeps the rest
      if (errno == EPIPE || errno == ECONNRESET || shut_) {  // the host is gone: no one reads
        pending_.clear();
        return;
      }
      throw std::system_error(errno, std::system_category(), "falcon peer: send");
    }
    sent += taken;
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(sent));
}

std::unique_ptr<LoopbackPeer> make_loopback_peer(const config::Config& cfg, io::UniqueFd fd) {
  return std::make_unique<FalconPeer>(cfg, std::move(fd));
}

}  // namespace hapticd::sim::falcon
