// The Novint Falcon's wire, pure (docs/drivers/falcon.md): the FTDI FT232's vendor requests that
// set its UART up, the bootloader's handshake and echo, and the 16-byte packets Novint's firmware
// exchanges once a tick. Read from libnifalcon (github libnifalcon/libnifalcon, BSD):
// src/comm/FalconCommLibUSB.cpp (setFirmwareMode, setNormalMode), src/core/FalconFirmware.cpp
// (loadFirmware), src/firmware/FalconFirmwareNovintSDK.cpp (formatInput, formatOutput) and
// include/falcon/core/FalconKinematic.h, FalconGeometry.h (getTheta's constants). This is our
// own formulation of what they do; where we differ from the library, the comment says so.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace hapticd::drivers::falcon {

// The FT232 on the Falcon answers to Novint's ids, not FTDI's 0403:6001.
inline constexpr std::uint16_t kVendorId = 0x0403;
inline constexpr std::uint16_t kProductId = 0xCB48;
inline constexpr unsigned char kEndpointOut = 0x02;
inline constexpr unsigned char kEndpointIn = 0x81;
// Full speed: the chip sends IN data in 64-byte USB packets, each led by 2 modem status bytes,
// and a packet of the status bytes alone every latency-timer period when it has no data.
inline constexpr std::size_t kUsbPacketBytes = 64;
inline constexpr std::size_t kModemStatusBytes = 2;

// One FTDI vendor request: bmRequestType 0x40 (vendor, host to device), wIndex 0 (the only
// interface), no data stage.
struct FtdiRequest {
  std::uint8_t request = 0;
  std::uint16_t value = 0;
  std::string_view what;  // for the error that names a refused request
};
inline constexpr std::uint8_t kFtdiRequestType = 0x40;

// Before the bootloader handshake: both FIFOs purged, a 16 ms latency timer (libnifalcon: the
// firmware checks "tend to always fail" with less), 9600 baud 8N1, no flow control, RTS low,
// then DTR pulsed low to high (the pulse resets the microcontroller into its bootloader).
std::span<const FtdiRequest> bootloader_setup() noexcept;
// After the first check: DTR low and the loading rate, FTDI divisor 0x15 (3 MHz / 21, about
// 140 kbaud).
std::span<const FtdiRequest> loading_rate() noexcept;
// After the image: a 1 ms latency timer, FTDI divisor 2 (1.5 Mbaud; libnifalcon's 1456312),
// both FIFOs purged.
std::span<const FtdiRequest> normal_mode() noexcept;

// The bootloader's first check: "\nC\r" out, "\nD,\r" back (on Linux; a leading 0x00 on macOS,
// libnifalcon accepts both); the second: "A" out at the loading rate, "A" back. The data as
// sent and as received after the 2 modem status bytes.
inline constexpr std::array<unsigned char, 3> kCheckSend = {0x0A, 0x43, 0x0D};
inline constexpr std::array<unsigned char, 4> kCheckReply = {0x0A, 0x44, 0x2C, 0x0D};
inline constexpr unsigned char kLoadCheck = 0x41;
// Whether `data` (an IN transfer with its status bytes stripped) is the first check's reply.
bool is_check_reply(std::span<const unsigned char> data) noexcept;

// The image goes out in chunks of this many bytes, each echoed back byte for byte.
inline constexpr std::size_t kLoadChunkBytes = 128;
// Novint's firmware images as libnifalcon's firmware/ folder has them: novint_T0.bin and
// novint_T2.bin 7914 bytes, nvent_firmware.bin 8492, test_firmware.bin 7324. An image outside
// these bounds is no Falcon firmware (a wrong file: an empty one, a driver installer).
inline constexpr std::size_t kFirmwareMinBytes = 4096;
inline constexpr std::size_t kFirmwareMaxBytes = 16384;

// --- the firmware's packets: '<', 14 bytes of 4-bit nibbles plus 0x41 ('A'), '>' ---
inline constexpr std::size_t kPacketBytes = 16;
using Packet = std::array<unsigned char, kPacketBytes>;

// LED bits of byte 13 out (libnifalcon's FalconFirmware GREEN_LED, BLUE_LED, RED_LED); bit 0
// is the homing mode.
enum Led : std::uint8_t { kLedGreen = 0x2, kLedBlue = 0x4, kLedRed = 0x8 };

struct Command {
  std::array<std::int16_t, 3> motor{};  // each motor's command, counts (see counts_per_torque)
  std::uint8_t leds = 0;                // Led bits
  bool homing = false;                  // the firmware's homing mode
};

struct State {
  std::array<std::int16_t, 3> encoder{};  // each motor's encoder, relative to power-on
  std::uint8_t homed = 0;                 // bit i: motor i homed
  std::uint8_t grip = 0;                  // the grip's buttons, one bit each
};

enum class PacketError : std::uint8_t { kNone, kBadNibble };
std::string_view packet_error_name(PacketError e) noexcept;

// RT-safe: called every tick. Each motor's 16 bits, least significant nibble first.
Packet encode_command(const Command& c) noexcept;
// RT-safe: called every tick. A packet framed by '<' and '>' whose nibbles are each within
// 'A'..'P' (byte 13: within 'A' + 0x7F, homing bits 4-6, grip bits 0-3). libnifalcon masks
// whatever comes; a byte out of range here is a corrupted packet, counted, never read.
PacketError decode_state(const Packet& p, State& s) noexcept;

// The IN stream reassembled into packets: each USB packet's modem status bytes dropped, the
// data scanned for '<' ... '>' sixteen bytes apart (a byte lost or added misaligns the stream;
// libnifalcon then reads every later packet from the wrong offset: here the scan finds the next
// frame and counts the bytes skipped). Fixed storage: RT-safe.
class PacketStream {
 public:
  // RT-safe: called every tick. One IN transfer of `n` bytes as the chip sent it: a 2-byte
  // modem status at the start of each 64-byte USB packet.
  void feed_transfer(std::span<const unsigned char> transfer) noexcept;
  // RT-safe. Data bytes already without their modem status.
  void feed_data(std::span<const unsigned char> data) noexcept;
  // RT-safe: called every tick. The next complete frame, oldest first; false when none.
  bool next(Packet& out) noexcept;
  std::uint64_t skipped_bytes() const noexcept { return skipped_; }
  std::uint64_t overflowed_bytes() const noexcept { return overflowed_; }
  std::size_t buffered_bytes() const noexcept { return size_; }  // not yet a frame nor skipped
  void clear() noexcept { size_ = 0; }

 private:
  // Room for several packets: a tick's reply and the ones a late tick finds queued.
  std::array<unsigned char, 8 * kPacketBytes> buffer_{};
  std::size_t size_ = 0;
  std::uint64_t skipped_ = 0;
  std::uint64_t overflowed_ = 0;
};

// --- what the counts mean (FalconKinematic.h's getTheta, FalconKinematicStamper's getForces) ---
// The encoder: 320 slots read in quadrature (1280 counts a motor turn) on a 14.25 mm shaft
// driving the arm's 110 mm drum by a cable; 0 counts is the arm at about 35 degrees.
inline constexpr double kEncoderCountsPerTurn = 4 * 320;
inline constexpr double kShaftDiameter = 0.01425;  // m
inline constexpr double kDrumDiameter = 0.110;     // m
inline constexpr double kThetaAtZeroDeg = 35.0;
// RT-safe: called every tick. The arm's angle (rad; the delta kinematics' q_i) for a count.
double arm_angle(std::int16_t counts) noexcept;
// RT-safe. Its inverse, to the nearest count (a simulated Falcon's encoder), saturated at the
// int16 range (the count wraps there on the device; the arm never turns that far).
std::int16_t counts_at_angle(double angle_rad) noexcept;
// libnifalcon's command scale: 10000 counts per N m of torque at the arm, negated (a positive
// count turns the arm toward smaller angles). The firmware's own gain is not published.
inline constexpr double kCountsPerNewtonMetre = -10000.0;

// --- the loopback socketpair's messages (one SOCK_SEQPACKET message each): the FT232's
// control requests and bulk data, so the driver's load and exchange run unchanged against
// the simulated Falcon (sim/peers/falcon/).
enum LoopbackTag : unsigned char {
  kTagControl = 1,  // host -> device: request, value (little-endian u16)
  kTagBulkOut = 2,  // host -> device: the bytes of a bulk OUT transfer
  kTagBulkIn = 3,   // device -> host: one bulk IN transfer, modem status bytes included
};

}  // namespace hapticd::drivers::falcon
