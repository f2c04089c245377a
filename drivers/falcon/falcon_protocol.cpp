#include "drivers/falcon/falcon_protocol.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

namespace hapticd::drivers::falcon {
namespace {

// FTDI SIO requests (libftdi's names) and their values.
constexpr std::uint8_t kSioReset = 0, kSioModemCtrl = 1, kSioFlowCtrl = 2, kSioBaudRate = 3,
                       kSioData = 4, kSioLatencyTimer = 9;
constexpr std::uint16_t kPurgeRx = 1, kPurgeTx = 2;
constexpr std::uint16_t kDtrHigh = 0x0101, kDtrLow = 0x0100, kRtsLow = 0x0200;

constexpr FtdiRequest kBootloaderSetup[] = {
    {kSioReset, kPurgeRx, "purge the receive FIFO"},
    {kSioReset, kPurgeTx, "purge the transmit FIFO"},
    {kSioLatencyTimer, 16, "latency timer 16 ms"},
    {kSioBaudRate, 0x4138, "9600 baud"},
    {kSioData, 8, "8 data bits, no parity, 1 stop bit"},
    {kSioFlowCtrl, 0, "no flow control"},
    {kSioModemCtrl, kRtsLow, "RTS low"},
    {kSioModemCtrl, kDtrLow, "DTR low"},
    {kSioModemCtrl, kDtrHigh, "DTR high (reset into the bootloader)"},
};
constexpr FtdiRequest kLoadingRate[] = {
    {kSioModemCtrl, kDtrLow, "DTR low"},
    {kSioBaudRate, 0x15, "the loading rate (divisor 0x15)"},
};
constexpr FtdiRequest kNormalMode[] = {
    {kSioLatencyTimer, 1, "latency timer 1 ms"},
    {kSioBaudRate, 0x2, "the firmware's rate (divisor 2)"},
    {kSioReset, kPurgeRx, "purge the receive FIFO"},
    {kSioReset, kPurgeTx, "purge the transmit FIFO"},
};

constexpr unsigned char kStart = '<', kEnd = '>', kNibbleBase = 0x41;

}  // namespace

std::span<const FtdiRequest> bootloader_setup() noexcept { return kBootloaderSetup; }
std::span<const FtdiRequest> loading_rate() noexcept { return kLoadingRate; }
std::span<const FtdiRequest> normal_mode() noexcept { return kNormalMode; }

bool is_check_reply(std::span<const unsigned char> data) noexcept {
  const std::span<const unsigned char> reply(kCheckReply);
  if (data.size() == reply.size() + 1 && data[0] == 0x00) data = data.subspan(1);
  return std::ranges::equal(data, reply);
}

std::string_view packet_error_name(PacketError e) noexcept {
  switch (e) {
    case PacketError::kNone:
      return "none";
    case PacketError::kBadNibble:
      return "a byte out of the nibble range";
  }
  return "?";
}

Packet encode_command(const Command& c) noexcept {
  Packet p{};
  p[0] = kStart;
  p[kPacketBytes - 1] = kEnd;
  for (std::size_t m = 0; m < 3; ++m) {
    const auto bits = static_cast<std::uint16_t>(c.motor[m]);
    for (std::size_t n = 0; n < 4; ++n) {
      p[1 + 4 * m + n] = static_cast<unsigned char>(kNibbleBase + ((bits >> (4 * n)) & 0xF));
    }
  }
  const auto flags =
      static_cast<unsigned>((c.leds & (kLedGreen | kLedBlue | kLedRed)) | (c.homing ? 0x1 : 0x0));
  p[13] = static_cast<unsigned char>(kNibbleBase + flags);
  p[14] = kNibbleBase;
  return p;
}

PacketError decode_state(const Packet& p, State& s) noexcept {
  const auto nibble = [](unsigned char b) { return b >= kNibbleBase && b < kNibbleBase + 16; };
  for (std::size_t i = 1; i < 13; ++i) {
    if (!nibble(p[i])) return PacketError::kBadNibble;
  }
  if (p[13] < kNibbleBase || p[13] > kNibbleBase + 0x7F || !nibble(p[14])) {
    return PacketError::kBadNibble;
  }
  for (std::size_t m = 0; m < 3; ++m) {
    unsigned bits = 0;
    for (std::size_t n = 0; n < 4; ++n) bits |= unsigned(p[1 + 4 * m + n] - kNibbleBase) << (4 * n);
    s.encoder[m] = static_cast<std::int16_t>(static_cast<std::uint16_t>(bits));
  }
  const unsigned flags = p[13] - kNibbleBase;
  s.homed = static_cast<std::uint8_t>((flags >> 4) & 0x7);
  s.grip = static_cast<std::uint8_t>(flags & 0xF);
  return PacketError::kNone;
}

void PacketStream::feed_data(std::span<const unsigned char> data) noexcept {
  const std::size_t room = buffer_.size() - size_;
  const std::size_t n = std::min(room, data.size());
  if (n > 0)
    std::memcpy(buffer_.data() + size_, data.data(), n);  // an empty span's data() may be null
  size_ += n;
  overflowed_ += data.size() - n;  // a reader that fell this far behind lost these
}

void PacketStream::feed_transfer(std::span<const unsigned char> transfer) noexcept {
  while (!transfer.empty()) {
    const std::size_t usb = std::min(transfer.size(), kUsbPacketBytes);
    if (usb > kModemStatusBytes)
      feed_data(transfer.subspan(kModemStatusBytes, usb - kModemStatusBytes));
    transfer = transfer.subspan(usb);
  }
}

bool PacketStream::next(Packet& out) noexcept {
  std::size_t at = 0;
  bool found = false;
  while (at + kPacketBytes <= size_) {
    if (buffer_[at] == kStart && buffer_[at + kPacketBytes - 1] == kEnd) {
      found = true;
      break;
    }
    ++at;
  }
  if (!found) {
    // Keep what may still become a frame: the bytes from the last '<' that could start one.
    std::size_t keep = size_ >= kPacketBytes ? size_ - (kPacketBytes - 1) : 0;
    while (keep < size_ && buffer_[keep] != kStart) ++keep;
    at = keep;
  }
  skipped_ += at;
  if (found) std::memcpy(out.data(), buffer_.data() + at, kPacketBytes);
  const std::size_t consumed = found ? at + kPacketBytes : at;
  std::memmove(buffer_.data(), buffer_.data() + consumed, size_ - consumed);
  size_ -= consumed;
  return found;
}

double arm_angle(std::int16_t counts) noexcept {
  // Each count turns the shaft 1/1280 of a turn: pi D_shaft / 1280 of cable, which turns the
  // drum by that arc over its circumference, in degrees.
  const double cable = std::numbers::pi * kShaftDiameter / kEncoderCountsPerTurn * counts;
  const double deg = cable / (std::numbers::pi * kDrumDiameter) * 360.0 + kThetaAtZeroDeg;
  return deg * std::numbers::pi / 180.0;
}

std::int16_t counts_at_angle(double angle_rad) noexcept {
  const double per_rad = (arm_angle(1) - arm_angle(0));
  const double counts = std::round((angle_rad - arm_angle(0)) / per_rad);
  if (!std::isfinite(counts)) return 0;
  return static_cast<std::int16_t>(std::clamp(counts, -32768.0, 32767.0));
}

}  // namespace hapticd::drivers::falcon
