// The simulated Falcon's FT232 and its microcontroller's bootloader (docs/drivers/falcon.md,
// "The FTDI set-up and the bootloader"), as firmware_loader.cpp drives them: the chip's vendor
// requests (purges, DTR and RTS, the baud divisor, latency timer), the DTR pulse that resets the
// microcontroller into its bootloader, the two checks each answered only at its rate, the
// image's echo, and the firmware's start at divisor 2 after a plausible image. No socket and no
// plant: the peer (falcon_peer.h) carries the bytes, the firmware (falcon_firmware.h) runs once
// started. A UART at the wrong rate reads garbage: here that is silence, so a host at the wrong
// divisor sees nothing, as it would see no valid reply.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace hapticd::sim::falcon {

// What the microcontroller runs.
enum class McuMode : std::uint8_t {
  kBootloader,  // after power-on or a DTR pulse: answers the checks
  kLoading,     // the second check passed: echoes and keeps every byte (the image)
  kSilent,      // divisor 2 after an implausible image (or none): nothing runs, nothing answers
  kFirmware,    // Novint's firmware runs: the packets are the firmware's (falcon_firmware.h)
};

// What a vendor request did that the peer acts on.
enum class ChipEffect : std::uint8_t {
  kNone,
  kPurgeToHost,    // purge RX (value 1): what the device queued for the host is dropped
  kPurgeFromHost,  // purge TX (value 2): the host's OUT data not yet taken is dropped
  kReset,          // DTR low to high: the microcontroller reset (a running firmware stops)
  kFirmwareStarts  // divisor 2 after a plausible image
};

class Ft232Bootloader {
 public:
  // `ignore_first_pulse_checks`: the bootloader of the first DTR pulse never answers the first
  // check (the "load fails the first try, works the second" that libnifalcon's users report).
  explicit Ft232Bootloader(bool ignore_first_pulse_checks = false) noexcept
      : ignore_first_pulse_checks_(ignore_first_pulse_checks) {}

  // One vendor request (FTDI SIO request, value).
  ChipEffect control(std::uint8_t request, std::uint16_t value) noexcept;
  // A bulk OUT transfer while the firmware does not run (mode() != kFirmware): the bootloader's
  // answer, if any, appended to `to_host` (data bytes, no modem status).
  void bulk_out(std::span<const unsigned char> data, std::vector<unsigned char>& to_host);

  McuMode mode() const noexcept { return mode_; }
  std::uint16_t divisor() const noexcept { return divisor_; }
  std::uint16_t latency_ms() const noexcept { return latency_ms_; }
  bool dtr() const noexcept { return dtr_; }
  int pulses() const noexcept { return pulses_; }                      // DTR resets so far
  std::size_t image_bytes() const noexcept { return image_bytes_; }    // taken since the reset
  std::uint32_t image_checksum() const noexcept { return checksum_; }  // of those bytes
  int loads_completed() const noexcept { return loads_; }              // firmware starts

 private:
  ChipEffect modem_control(std::uint16_t value) noexcept;
  ChipEffect set_divisor(std::uint16_t value) noexcept;

  bool ignore_first_pulse_checks_;
  McuMode mode_ = McuMode::kBootloader;  // power-on: no firmware, the bootloader waits
  bool dtr_ = true;                      // a pulse is low then high, as the host sends it
  std::uint16_t divisor_ = 0x4138;       // the chip's power-on 9600 baud
  std::uint16_t latency_ms_ = 16;
  int pulses_ = 0;
  std::size_t image_bytes_ = 0;
  std::uint32_t checksum_ = 0;
  int loads_ = 0;
};

}  // namespace hapticd::sim::falcon
