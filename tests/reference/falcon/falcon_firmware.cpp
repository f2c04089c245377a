#include "falcon_firmware.h"

#include <algorithm>
#include <cmath>

namespace hapticd::reference::falcon {
namespace {

constexpr std::uint8_t kOffset = 0x41;  // every payload nibble rides on 'A'
constexpr std::array<std::uint8_t, 3> kCheck1{0x0A, 0x43, 0x0D};
constexpr std::array<std::uint8_t, 4> kCheck1Answer{0x0A, 0x44, 0x2C, 0x0D};
constexpr std::uint8_t kCheck2 = 0x41;
// SIO_MODEM_CTRL: the low byte the lines' state, the high byte which of them to set.
constexpr std::uint16_t kDtr = 0x0001, kRts = 0x0002, kDtrMask = 0x0100, kRtsMask = 0x0200;
constexpr std::size_t kFifoLimit = 512;  // the chip's buffer toward the host: more is lost
constexpr double kMaxPlantStep = 0.010;  // seconds of plant per packet at most

bool nibble(std::uint8_t b) { return b >= kOffset && b <= kOffset + 0x0F; }

Vec3 absolute_counts(const FalconMechanism& m) {
  const Vec3& t = m.arm_angles();
  return {counts_of_theta(t[0]), counts_of_theta(t[1]), counts_of_theta(t[2])};
}

}  // namespace

std::array<std::uint8_t, kPacket> encode_packet(const std::array<std::int16_t, 3>& values,
                                                std::uint8_t flags) {
  std::array<std::uint8_t, kPacket> p{};
  p[0] = '<';
  p[15] = '>';
  for (int i = 0; i < 3; ++i) {
    const auto v = static_cast<std::uint16_t>(values[i]);
    for (int n = 0; n < 4; ++n) {
      p[1 + 4 * i + n] = static_cast<std::uint8_t>(((v >> (4 * n)) & 0x0F) + kOffset);
    }
  }
  p[13] = static_cast<std::uint8_t>(flags + kOffset);
  p[14] = kOffset;
  return p;
}

bool decode_packet(const std::uint8_t* p, Decoded& out) {
  if (p[0] != '<' || p[15] != '>') return false;
  if (!std::all_of(p + 1, p + 15, nibble)) return false;
  for (int i = 0; i < 3; ++i) {
    std::uint16_t v = 0;
    for (int n = 0; n < 4; ++n)
      v |= static_cast<std::uint16_t>((p[1 + 4 * i + n] - kOffset) << 4 * n);
    out.values[i] = static_cast<std::int16_t>(v);
  }
  out.flags = static_cast<std::uint8_t>(p[13] - kOffset);
  return true;
}

FalconFirmware::FalconFirmware(const FirmwareOptions& o) : o_(o), mechanism_(o.mechanism) {
  stage_ = o_.fail_first_try ? Stage::kDeaf : Stage::kAwaitCheck1;
  power_on_counts_ = last_counts_ = absolute_counts(mechanism_);
}

bool FalconFirmware::control(std::uint8_t request, std::uint16_t value) {
  switch (request) {
    case kSioReset:
      // 0 resets the chip (both buffers), 1 purges toward the host, 2 toward the device (the
      // model hands host bytes to the microcontroller at once: nothing waits there).
      if (value == 0 || value == 1) {
        fifo_.clear();
        ++purges_;
      }
      return value <= 2;
    case kSioModemCtrl: {
      if (value & kRtsMask) rts_ = (value & kRts) != 0;
      if (value & kDtrMask) {
        const bool was = dtr_;
        dtr_ = (value & kDtr) != 0;
        if (!was && dtr_) reset_mcu();
      }
      return true;
    }
    case kSioBaudRate:
      divisor_ = value;
      // setNormalMode: the host leaves the bootloader's rate; a loaded image starts.
      if (value == kDivisorFirmware && stage_ == Stage::kLoading && !hung_) {
        const bool plausible = image_.size() >= kImageMin && image_.size() <= kImageMax;
        stage_ = plausible ? Stage::kRunning : Stage::kRejected;
        rx_.clear();
      }
      return true;
    case kSioLatency:
      if (value < 1 || value > 255) return false;
      latency_ = static_cast<std::uint8_t>(value);
      return true;
    case kSioFlowCtrl:
    case kSioData:
      return true;
    default:
      return false;
  }
}

void FalconFirmware::reset_mcu() {
  ++resets_;
  // The first start's bootloader misses check 1 when asked to (a real device sometimes needs
  // libnifalcon's retries).
  stage_ = (o_.fail_first_try && resets_ == 1) ? Stage::kDeaf : Stage::kAwaitCheck1;
  image_.clear();
  rx_.clear();
  check_.clear();
  homing_ = false;
  homed_ = 0;
  leds_ = 0;
  mechanism_.set_motor_commands({0, 0, 0});  // the motors' drive restarts unpowered
  power_on_counts_ = last_counts_ = absolute_counts(mechanism_);
  hung_ = false;  // a reset is what frees a hung microcontroller
}

void FalconFirmware::receive(std::span<const std::uint8_t> bytes, double now) {
  if (hung_) return;
  if (stage_ == Stage::kRunning) return firmware_bytes(bytes, now);
  for (const std::uint8_t b : bytes) bootloader(b);
}

void FalconFirmware::bootloader(std::uint8_t byte) {
  switch (stage_) {
    case Stage::kAwaitCheck1:
    case Stage::kAwaitCheck2:
      if (stage_ == Stage::kAwaitCheck1 && divisor_ == kDivisor9600) {
        check_.push_back(byte);
        if (check_.size() > kCheck1.size()) check_.erase(check_.begin());
        if (std::equal(check_.begin(), check_.end(), kCheck1.begin(), kCheck1.end())) {
          send(kCheck1Answer);
          check_.clear();
          stage_ = Stage::kAwaitCheck2;
        }
      } else if (stage_ == Stage::kAwaitCheck2 && divisor_ == kDivisorCheck2 && !dtr_ &&
                 byte == kCheck2) {
        send({&kCheck2, 1});
        stage_ = Stage::kLoading;
      }
      return;  // at any other rate the byte arrives garbled
    case Stage::kLoading:
      image_.push_back(byte);
      send({&byte, 1});
      return;
    default:
      return;  // deaf, or an image it would not start
  }
}

void FalconFirmware::firmware_bytes(std::span<const std::uint8_t> bytes, double now) {
  rx_.insert(rx_.end(), bytes.begin(), bytes.end());
  std::size_t at = 0;
  while (true) {
    // Skip to a '<': whatever came before it was no command.
    const auto start = std::find(rx_.begin() + static_cast<std::ptrdiff_t>(at), rx_.end(), '<');
    const auto skipped = static_cast<std::size_t>(start - rx_.begin()) - at;
    if (skipped > 0) ++malformed_;
    at += skipped;
    if (rx_.size() - at < kPacket) break;
    Decoded d{};
    if (decode_packet(rx_.data() + at, d)) {
      command(rx_.data() + at, now);
      at += kPacket;
    } else {
      ++malformed_;
      at += 1;  // a '<' that starts no packet
    }
  }
  rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(at));
}

void FalconFirmware::command(const std::uint8_t* packet, double now) {
  Decoded d{};
  decode_packet(packet, d);
  if (last_step_ >= 0) mechanism_.step(std::clamp(now - last_step_, 0.0, kMaxPlantStep));
  last_step_ = now;
  update_homing();
  mechanism_.set_motor_commands(d.values);
  leds_ = d.flags & 0x0E;
  homing_ = (d.flags & 0x01) != 0;
  ++packets_;
  if (o_.silent_firmware) return;
  const auto flags = static_cast<std::uint8_t>((homed_ << 4) | (o_.buttons & 0x0F));
  send(encode_packet(encoders(), flags));
}

void FalconFirmware::update_homing() {
  const Vec3 now = absolute_counts(mechanism_);
  for (int i = 0; i < 3; ++i) {
    const bool crossed = (last_counts_[i] <= 0) != (now[i] <= 0);
    if (homing_ && crossed) homed_ |= static_cast<std::uint8_t>(1u << i);
  }
  last_counts_ = now;
}

std::array<std::int16_t, 3> FalconFirmware::encoders() const {
  const Vec3 now = absolute_counts(mechanism_);
  std::array<std::int16_t, 3> out{};
  for (int i = 0; i < 3; ++i) {
    const double c = (homed_ >> i) & 1 ? now[i] : now[i] - power_on_counts_[i];
    // The counter is 16 bits wide on the wire: it wraps.
    out[i] = static_cast<std::int16_t>(static_cast<std::uint16_t>(std::lround(c) & 0xFFFF));
  }
  return out;
}

void FalconFirmware::send(std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t b : bytes) {
    if (fifo_.size() < kFifoLimit) fifo_.push_back(b);
  }
}

std::vector<std::uint8_t> FalconFirmware::take(std::size_t max) {
  const std::size_t n = std::min(max, fifo_.size());
  std::vector<std::uint8_t> out(fifo_.begin(), fifo_.begin() + static_cast<std::ptrdiff_t>(n));
  fifo_.erase(fifo_.begin(), fifo_.begin() + static_cast<std::ptrdiff_t>(n));
  return out;
}

}  // namespace hapticd::reference::falcon
