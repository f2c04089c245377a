// An FtdiLink over a simulated Falcon's bootloader and firmware, as far as the loader's tests
// need one: DTR pulsed low to high enters the bootloader, which answers its two checks at
// their rates and echoes the image; divisor 2 starts the firmware, which answers each packet.
// It speaks through the codec's constants, so it proves the loader's steps and their records,
// not the reading of libnifalcon (the reference Falcon does that, sharing none of the codec).
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "drivers/falcon/ftdi_link.h"

namespace hapticd::drivers::falcon::testing {

class FakeFalconLink final : public FtdiLink {
 public:
  int ignore_first_pulses = 0;   // DTR pulses whose bootloader ignores the first check
  long corrupt_echo_at = -1;     // image byte echoed wrong (every try)
  bool silent_firmware = false;  // the firmware never answers
  bool unplugged = false;

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
    } else if (divisor == 2 && loading_ && data.size() == kPacketBytes && !silent_firmware) {
      ++packets_answered;
      push(encode_command(Command{}));  // a state of zero counts, nothing homed
    }
    return true;
  }

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
  void pulse() {
    dtr_ = true;
    ++pulses;
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
  std::deque<unsigned char> pending_;
};

}  // namespace hapticd::drivers::falcon::testing
