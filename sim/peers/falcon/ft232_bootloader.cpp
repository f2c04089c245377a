#include "sim/peers/falcon/ft232_bootloader.h"

#include <algorithm>

#include "drivers/falcon/falcon_protocol.h"

namespace hapticd::sim::falcon {
namespace {

namespace df = drivers::falcon;

// FTDI SIO requests and values (libftdi's names), as the codec's request tables send them.
constexpr std::uint8_t kSioReset = 0, kSioModemCtrl = 1, kSioBaudRate = 3, kSioLatencyTimer = 9;
constexpr std::uint16_t kPurgeRx = 1, kPurgeTx = 2;
constexpr std::uint16_t kDtrLow = 0x0100, kDtrHigh = 0x0101;
// The divisors: the checks' 9600 baud, the loading rate, the firmware's 1.5 Mbaud.
constexpr std::uint16_t kCheckDivisor = 0x4138, kLoadDivisor = 0x15, kFirmwareDivisor = 0x2;

}  // namespace

ChipEffect Ft232Bootloader::control(std::uint8_t request, std::uint16_t value) noexcept {
  switch (request) {
    case kSioReset:
      if (value == kPurgeRx) return ChipEffect::kPurgeToHost;
      if (value == kPurgeTx) return ChipEffect::kPurgeFromHost;
      return ChipEffect::kNone;  // 0: a reset of the chip's SIO, nothing the device holds
    case kSioModemCtrl:
      return modem_control(value);
    case kSioBaudRate:
      return set_divisor(value);
    case kSioLatencyTimer:
      latency_ms_ = value;
      return ChipEffect::kNone;
    default:  // flow control, data format: the simulated UART frames bytes whatever they say
      return ChipEffect::kNone;
  }
}

ChipEffect Ft232Bootloader::modem_control(std::uint16_t value) noexcept {
  if (value == kDtrLow) dtr_ = false;
  if (value != kDtrHigh) return ChipEffect::kNone;  // RTS: not wired to the microcontroller
  const bool pulse = !dtr_;
  dtr_ = true;
  if (!pulse) return ChipEffect::kNone;
  // The reset: whatever ran stops and the image is forgotten (it lives in RAM).
  ++pulses_;
  mode_ = McuMode::kBootloader;
  image_bytes_ = 0;
  checksum_ = 0;
  return ChipEffect::kReset;
}

ChipEffect Ft232Bootloader::set_divisor(std::uint16_t value) noexcept {
  divisor_ = value;
  if (value != kFirmwareDivisor || mode_ != McuMode::kLoading) return ChipEffect::kNone;
  // The bootloader jumps to what it took; a wrong file (empty, an installer) runs nothing.
  if (image_bytes_ < df::kFirmwareMinBytes || image_bytes_ > df::kFirmwareMaxBytes) {
    mode_ = McuMode::kSilent;
    return ChipEffect::kNone;
  }
  mode_ = McuMode::kFirmware;
  ++loads_;
  return ChipEffect::kFirmwareStarts;
}

void Ft232Bootloader::bulk_out(std::span<const unsigned char> data,
                               std::vector<unsigned char>& to_host) {
  switch (mode_) {
    case McuMode::kBootloader: {
      const bool deaf = ignore_first_pulse_checks_ && pulses_ == 1;
      if (divisor_ == kCheckDivisor && std::ranges::equal(data, df::kCheckSend) && !deaf) {
        to_host.insert(to_host.end(), df::kCheckReply.begin(), df::kCheckReply.end());
      } else if (divisor_ == kLoadDivisor && !dtr_ && data.size() == 1 &&
                 data[0] == df::kLoadCheck) {
        to_host.push_back(df::kLoadCheck);
        mode_ = McuMode::kLoading;
      }
      return;
    }
    case McuMode::kLoading:
      if (divisor_ != kLoadDivisor) return;  // at another rate the bytes are garbage: dropped
      for (const unsigned char b : data) {
        checksum_ = checksum_ * 31u + b;
        ++image_bytes_;
      }
      to_host.insert(to_host.end(), data.begin(), data.end());
      return;
    case McuMode::kSilent:
    case McuMode::kFirmware:  // the peer gives the firmware its packets
      return;
  }
}

}  // namespace hapticd::sim::falcon
