// A FalconTransport over a simulated Falcon's bootloader and firmware, in the test's own
// thread, as far as the loader's and the Device's tests need one: DTR pulsed low to high enters
// the bootloader, which answers its two checks at their rates and echoes the image; divisor 2
// starts the firmware, which answers each packet with the encoders the test sets, and sets the
// homed bits once `homing_packets` packets have asked for homing.
// It speaks through the codec's constants, so it proves the loader's steps and their records,
// not the reading of libnifalcon (the reference Falcon does that, sharing none of the codec).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "drivers/falcon/falcon_transport.h"
#include "drivers/falcon/firmware_loader.h"

namespace hapticd::drivers::falcon::testing {

// Short waits: the simulated device answers at once or never.
inline constexpr LoaderTiming kFast{5, 3, 50, 5, 3};

class FakeFalconLink final : public FalconTransport {
 public:
  int ignore_first_pulses = 0;   // DTR pulses whose bootloader ignores the first check
  long corrupt_echo_at = -1;     // image byte echoed wrong (every try)
  bool silent_firmware = false;  // the firmware never answers
  bool unplugged = false;
  bool firmware_running = false;  // loaded before (a restarted hapticd finds it running)
  int homing_packets = 3;         // packets with the homing bit before all three are homed
  bool lose_homing = false;       // the firmware drops its homed bits
  bool corrupt_next = false;      // the next answer has a byte out of range
  std::array<std::int16_t, 3> encoders{};

  std::array<std::int16_t, 3> last_motor{};
  std::uint8_t last_leds = 0;
  bool last_homing = false;

  std::vector<unsigned char> image;  // what the bootloader took on its last try
  int pulses = 0;
  std::uint16_t divisor = 0;
  std::uint16_t latency_ms = 0;
  int packets_answered = 0;

  bool control(const FtdiRequest& r, std::string& error) override {
    if (unplugged) {
      error = "LIBUSB_ERROR_NO_DEVICE";
      return false;
    }
    if (r.request == 0 && r.value == 1) pending_.clear();  // purge RX: what the host has not read
    if (r.request == 1 && r.value == 0x0100) dtr_ = false;
    if (r.request == 1 && r.value == 0x0101 && !dtr_) pulse();
    if (r.request == 3) divisor = r.value;
    if (r.request == 9) latency_ms = r.value;
    return true;
  }

  bool write(std::span<const unsigned char> data, int, std::string& error) override {
    if (unplugged) {
      error = "LIBUSB_ERROR_NO_DEVICE";
      return false;
    }
    if (divisor == 0x4138 && bootloader_ && std::ranges::equal(data, kCheckSend)) {
      if (pulses > ignore_first_pulses) push(kCheckReply);
    } else if (divisor == 0x15 && bootloader_ && !loading_) {
      loading_ = data.size() == 1 && data[0] == kLoadCheck;
      if (loading_) push(std::vector<unsigned char>{kLoadCheck});
    } else if (divisor == 0x15 && loading_) {
      for (const unsigned char b : data) {
        const bool wrong = static_cast<long>(image.size()) == corrupt_echo_at;
        image.push_back(b);
        push(std::vector<unsigned char>{static_cast<unsigned char>(wrong ? b ^ 0xFF : b)});
      }
    } else if (divisor == 2 && (loading_ || firmware_running) && data.size() == kPacketBytes) {
      answer(data);
    }
    return true;
  }

  std::string describe() const override { return "falcon (test)"; }
  TransportIo send(const Packet& p) noexcept override {
    if (unplugged) return TransportIo::kError;
    std::string error;
    write(p, 0, error);
    return TransportIo::kOk;
  }
  TransportIo receive(PacketStream& stream) noexcept override {
    if (unplugged) return TransportIo::kError;
    std::vector<unsigned char> data(pending_.begin(), pending_.end());
    pending_.clear();
    stream.feed_data(data);
    return TransportIo::kOk;
  }
  int error() const noexcept override { return unplugged ? 19 : 0; }  // ENODEV
  std::int64_t received_ns() const noexcept override { return 0; }
  void emergency(const Packet&) noexcept override {}

  int read(std::span<unsigned char> buffer, int, std::string& error) override {
    if (unplugged) {
      error = "LIBUSB_ERROR_NO_DEVICE";
      return -1;
    }
    buffer[0] = 0x31;  // the modem status the chip leads every packet with
    buffer[1] = 0x60;
    std::size_t n = kModemStatusBytes;
    while (n < kUsbPacketBytes && !pending_.empty()) {
      buffer[n++] = pending_.front();
      pending_.pop_front();
    }
    return static_cast<int>(n);
  }

 private:
  void answer(std::span<const unsigned char> data) {
    Packet in;
    std::copy(data.begin(), data.end(), in.begin());
    State cmd;  // a command has a state's layout: the motors, byte 13 the flags
    if (decode_state(in, cmd) != PacketError::kNone) return;
    last_motor = cmd.encoder;
    last_leds = cmd.grip & 0xE;
    last_homing = (cmd.grip & 0x1) != 0;
    if (silent_firmware) return;
    ++packets_answered;
    if (last_homing) ++homing_seen_;
    Command out;  // a state has a command's layout: the encoders, byte 13 homed << 4 | grip
    out.motor = encoders;
    const bool homed = homing_seen_ >= homing_packets && !lose_homing;
    Packet p = encode_command(out);
    p[13] = static_cast<unsigned char>(0x41 + (homed ? 0x70 : 0));
    if (corrupt_next) p[5] = 0x20;
    corrupt_next = false;
    push(p);
  }

  void pulse() {
    dtr_ = true;
    ++pulses;
    firmware_running = false;  // the reset stops a running firmware
    bootloader_ = true;
    loading_ = false;
    image.clear();
    pending_.clear();
  }
  template <typename Bytes>
  void push(const Bytes& b) {
    pending_.insert(pending_.end(), b.begin(), b.end());
  }

  bool dtr_ = true;
  bool bootloader_ = false;
  bool loading_ = false;
  int homing_seen_ = 0;
  std::deque<unsigned char> pending_;
};

}  // namespace hapticd::drivers::falcon::testing
