#include "drivers/falcon/firmware_loader.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "base/clock.h"
#include "base/hex.h"

namespace hapticd::drivers::falcon {
namespace {

std::string hex_bytes(std::span<const unsigned char> bytes) {
  if (bytes.empty()) return "nothing";
  std::string s;
  for (const unsigned char b : bytes.first(std::min<std::size_t>(bytes.size(), 24))) {
    if (!s.empty()) s += ' ';
    s += base::hex(b, 2).substr(2);
  }
  if (bytes.size() > 24) s += " ... (" + std::to_string(bytes.size()) + " bytes)";
  return s;
}

// One try's steps; a failed step throws this, caught by the try.
struct StepFailed {
  std::string step;
  std::string saw;
};

class Try {
 public:
  Try(FtdiLink& link, const LoaderTiming& t) : link_(link), t_(t) {}

  void requests(std::span<const FtdiRequest> rs) {
    for (const FtdiRequest& r : rs) {
      std::string error;
      if (!link_.control(r, error)) {
        throw StepFailed{"FTDI request '" + std::string(r.what) + "' refused", error};
      }
    }
  }

  void write(std::span<const unsigned char> data, const std::string& step) {
    std::string error;
    if (!link_.write(data, t_.echo_ms, error)) throw StepFailed{step + ": write failed", error};
  }

  // Data bytes (modem status dropped) until `n` arrived or `timeout_ms` passed.
  std::vector<unsigned char> collect(std::size_t n, int timeout_ms, const std::string& step) {
    std::vector<unsigned char> data;
    const std::int64_t deadline = base::monotonic_ms() + timeout_ms;
    std::vector<unsigned char> buffer(4 * kUsbPacketBytes);
    while (data.size() < n) {
      const auto left = static_cast<int>(deadline - base::monotonic_ms());
      if (left <= 0) break;
      std::string error;
      const int got = link_.read(buffer, left, error);
      if (got < 0) throw StepFailed{step + ": read failed (" + error + ")", hex_bytes(data)};
      for (int k = 0; k < got; ++k) {
        if (static_cast<std::size_t>(k) % kUsbPacketBytes >= kModemStatusBytes) {
          data.push_back(buffer[static_cast<std::size_t>(k)]);
        }
      }
    }
    return data;
  }

  void first_check() {
    std::vector<unsigned char> seen;
    for (int i = 0; i < t_.check_writes; ++i) {
      write(kCheckSend, "the bootloader's first check");
      seen = collect(kCheckReply.size(), t_.reply_ms, "the bootloader's first check");
      // A macOS-style leading zero arrives as one byte more: take it too if it is there.
      if (seen.size() == kCheckReply.size() && seen[0] == 0x00) {
        const auto more = collect(1, t_.reply_ms, "the bootloader's first check");
        seen.insert(seen.end(), more.begin(), more.end());
      }
      if (is_check_reply(seen)) return;
    }
    throw StepFailed{"no answer \"0a 44 2c 0d\" to the bootloader's first check (" +
                         std::to_string(t_.check_writes) + " writes)",
                     hex_bytes(seen)};
  }

  void second_check() {
    const unsigned char a[1] = {kLoadCheck};
    write(a, "the bootloader's second check");
    const auto seen = collect(1, t_.reply_ms, "the bootloader's second check");
    if (seen.size() != 1 || seen[0] != kLoadCheck) {
      throw StepFailed{"no answer \"41\" to the bootloader's second check", hex_bytes(seen)};
    }
  }

  void image(std::span<const unsigned char> image) {
    for (std::size_t at = 0; at < image.size(); at += kLoadChunkBytes) {
      const auto chunk = image.subspan(at, std::min(kLoadChunkBytes, image.size() - at));
      const std::string step = "the image's echo at byte " + std::to_string(at);
      write(chunk, step);
      const auto echo = collect(chunk.size(), t_.echo_ms, step);
      if (!std::ranges::equal(echo, chunk)) {
        throw StepFailed{step + " (" + std::to_string(echo.size()) + " of " +
                             std::to_string(chunk.size()) + " bytes, or different ones)",
                         hex_bytes(echo)};
      }
    }
  }

  // The firmware runs: a packet with the LEDs off answered by a well-formed one.
  void firmware_answers() {
    const Packet out = encode_command(Command{});
    std::vector<unsigned char> seen;
    PacketStream stream;
    for (int i = 0; i < t_.answer_packets; ++i) {
      write(out, "the firmware's first packet");
      const auto got = collect(kPacketBytes, t_.answer_ms, "the firmware's first packet");
      seen.insert(seen.end(), got.begin(), got.end());
      stream.feed_data(got);
      Packet p;
      State s;
      while (stream.next(p)) {
        if (decode_state(p, s) == PacketError::kNone) return;
      }
    }
    throw StepFailed{
        "the firmware never answered a packet (" + std::to_string(t_.answer_packets) + " sent)",
        hex_bytes(seen)};
  }

 private:
  FtdiLink& link_;
  const LoaderTiming& t_;
};

}  // namespace

std::vector<unsigned char> read_firmware_image(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the Falcon's firmware image");
  std::vector<unsigned char> image{std::istreambuf_iterator<char>(in),
                                   std::istreambuf_iterator<char>()};
  if (image.size() < kFirmwareMinBytes || image.size() > kFirmwareMaxBytes) {
    throw std::runtime_error(
        path + ": " + std::to_string(image.size()) + " bytes is no Falcon firmware image (" +
        std::to_string(kFirmwareMinBytes) + " to " + std::to_string(kFirmwareMaxBytes) +
        " bytes; Novint's are 7324 to 8492: libnifalcon's firmware/ folder, from the Novint SDK)");
  }
  return image;
}

LoadResult load_firmware(FtdiLink& link, std::span<const unsigned char> image, int max_tries,
                         const LoaderTiming& timing) {
  LoadResult r;
  for (int n = 0; n < max_tries && !r.loaded; ++n) {
    Try t(link, timing);
    try {
      t.requests(bootloader_setup());
      t.first_check();
      t.requests(loading_rate());
      t.second_check();
      t.image(image);
      t.requests(normal_mode());
      t.firmware_answers();
      r.tries.push_back(LoadTry{});
      r.loaded = true;
    } catch (const StepFailed& f) {
      r.tries.push_back(LoadTry{f.step, f.saw});
    }
  }
  return r;
}

bool firmware_running(FtdiLink& link, const LoaderTiming& timing) {
  Try t(link, timing);
  try {
    t.requests(normal_mode());
    t.firmware_answers();
    return true;
  } catch (const StepFailed&) {
    return false;
  }
}

std::string describe(const LoadResult& r) {
  std::string s;
  for (std::size_t i = 0; i < r.tries.size(); ++i) {
    if (!s.empty()) s += "; ";
    s += "try " + std::to_string(i + 1) + ": ";
    s += r.tries[i].failed_at.empty() ? "loaded" : r.tries[i].failed_at + ", saw " + r.tries[i].saw;
  }
  return s;
}

}  // namespace hapticd::drivers::falcon
