// The reference Novint Falcon's byte-level behaviour, no I/O: the FT232 USB serial chip in
// front (its vendor requests, the FIFO toward the host) and the microcontroller behind it (the
// bootloader, then the firmware a host loads). Written from libnifalcon at
// f7c727aa24403ea10dc1507d7d396eeb7d55564a (BSD, reverse-engineered from the device):
// src/comm/FalconCommLibUSB.cpp (setFirmwareMode, setNormalMode: the FTDI requests and the
// bootloader's two checks), src/core/FalconFirmware.cpp (loadFirmware: the image echoed byte
// for byte) and src/firmware/FalconFirmwareNovintSDK.cpp (formatInput/formatOutput: the
// 16-byte packets). It shares no code with drivers/.
//
// Modelling choices (the firmware's source is not public; these are what libnifalcon's host
// steps need and what its comments say of the device):
// - DTR is the microcontroller's reset: each DTR low->high edge restarts it in the bootloader
//   (a running firmware is lost). The bootloader answers check 1 (0a 43 0d -> 0a 44 2c 0d) only
//   while the chip runs at 9600 baud (divisor 0x4138), and check 2 ('A' -> 'A') only at divisor
//   0x15 with DTR low: at any other rate the bytes arrive garbled and are ignored. Check 1 is
//   answered once per reset (then the bootloader waits for 'A'), so libnifalcon's loop of up
//   to 100 check 1s, when a read missed the answer, finds one answer, not several.
// - After check 2 it echoes every byte and keeps it as the image. The host's switch to divisor
//   2 (setNormalMode) starts the image when its size is plausible (4096..16384 bytes; Novint's
//   images are 7324..8492); otherwise the device stays silent until the next DTR pulse.
// - The firmware answers each well-formed 16-byte command with one 16-byte state packet.
//   A command is '<', 12 nibble bytes (three int16, least significant nibble first, each
//   + 0x41), byte 13 (LEDs green 0x2, blue 0x4, red 0x8, homing mode 0x1, + 0x41), 0x41, '>'.
//   Anything else is skipped up to the next '<' and counted as malformed.
// - Encoders count from the microcontroller's last start, power-on or a DTR pulse (incremental
//   encoders know no absolute position; its homed bits go with it). In
//   homing mode a motor whose arm crosses its index, at arm angle 35 degrees (getTheta's count
//   0), is homed: its bit (4 + motor) is set in the state packet's byte 13 and its count is
//   absolute from then on (0 at 35 degrees). libnifalcon's FalconCLIBase::calibrateDevice asks
//   the user to move the grip all the way out and push it in: that sweeps every arm through it.
// - The plant (falcon_mechanism.h) is stepped by the clock: each command packet advances it by
//   the time since the last one (at most 10 ms), then the packet's torques apply.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "falcon_mechanism.h"

namespace hapticd::reference::falcon {

// FTDI vendor requests (bRequest) and the values libnifalcon sends.
inline constexpr std::uint8_t kSioReset = 0, kSioModemCtrl = 1, kSioFlowCtrl = 2, kSioBaudRate = 3,
                              kSioData = 4, kSioLatency = 9;
inline constexpr std::uint16_t kDivisor9600 = 0x4138, kDivisorCheck2 = 0x15,
                               kDivisorFirmware = 0x02;
inline constexpr std::size_t kPacket = 16;
inline constexpr std::size_t kImageMin = 4096, kImageMax = 16384;

struct FirmwareOptions {
  MechanismOptions mechanism;
  bool fail_first_try = false;   // the bootloader ignores check 1 after the first DTR pulse
  bool silent_firmware = false;  // the loaded firmware never answers
  std::uint8_t buttons = 0;      // grip buttons, bits 0..3
};

enum class Stage { kDeaf, kAwaitCheck1, kAwaitCheck2, kLoading, kRejected, kRunning };

class FalconFirmware {
 public:
  explicit FalconFirmware(const FirmwareOptions& o = {});

  // An FTDI vendor request (bmRequestType 0x40); false stalls it.
  bool control(std::uint8_t request, std::uint16_t value);
  // Bytes from the host's bulk OUT; `now` is seconds on any monotonic clock.
  void receive(std::span<const std::uint8_t> bytes, double now);
  // Up to `max` bytes of the FIFO toward the host (the chip adds the modem status).
  std::vector<std::uint8_t> take(std::size_t max);
  std::size_t pending() const { return fifo_.size(); }
  // Bytes taken but never delivered (the USB side took its packet back) go first again.
  void put_back(std::span<const std::uint8_t> bytes) {
    fifo_.insert(fifo_.begin(), bytes.begin(), bytes.end());
  }
  // Bumped by each purge of the host-bound FIFO: whatever the chip had queued is gone.
  std::uint64_t purges() const { return purges_; }
  std::uint8_t latency_ms() const { return latency_; }

  // Test switches.
  // The microcontroller stops until a DTR pulse resets it; the chip still answers.
  void hang() { hung_ = true; }
  void set_buttons(std::uint8_t b) { o_.buttons = b & 0x0F; }

  Stage stage() const { return stage_; }
  std::uint16_t divisor() const { return divisor_; }
  bool dtr() const { return dtr_; }
  std::size_t image_size() const { return image_.size(); }
  std::uint64_t packets() const { return packets_; }
  std::uint64_t malformed() const { return malformed_; }
  std::uint64_t resets() const { return resets_; }
  std::uint8_t leds() const { return leds_; }
  bool homing_mode() const { return homing_; }
  std::uint8_t homed() const { return homed_; }
  // The counts the state packet reports now.
  std::array<std::int16_t, 3> encoders() const;
  FalconMechanism& mechanism() { return mechanism_; }
  const FalconMechanism& mechanism() const { return mechanism_; }

 private:
  void reset_mcu();
  void bootloader(std::uint8_t byte);
  void firmware_bytes(std::span<const std::uint8_t> bytes, double now);
  void command(const std::uint8_t* packet, double now);
  void update_homing();
  void send(std::span<const std::uint8_t> bytes);

  FirmwareOptions o_;
  FalconMechanism mechanism_;
  Stage stage_ = Stage::kAwaitCheck1;
  std::deque<std::uint8_t> fifo_;
  std::vector<std::uint8_t> image_, rx_, check_;
  std::uint16_t divisor_ = kDivisor9600;
  std::uint8_t latency_ = 16;
  bool dtr_ = false, rts_ = false, hung_ = false, homing_ = false;
  std::uint8_t leds_ = 0, homed_ = 0;
  std::uint64_t purges_ = 0, packets_ = 0, malformed_ = 0, resets_ = 0;
  Vec3 power_on_counts_{};  // each arm's absolute count at power-on
  Vec3 last_counts_{};      // for the index crossing
  double last_step_ = -1;
};

// The state packet for counts, homed bits and buttons (what the device sends), and a command's
// fields (what the host sends), both as the wire has them.
std::array<std::uint8_t, kPacket> encode_packet(const std::array<std::int16_t, 3>& values,
                                                std::uint8_t flags);
struct Decoded {
  std::array<std::int16_t, 3> values;
  std::uint8_t flags;
};
bool decode_packet(const std::uint8_t* p, Decoded& out);

}  // namespace hapticd::reference::falcon
