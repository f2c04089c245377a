// libFuzzer target for the Falcon's codec (drivers/falcon/falcon_protocol.h): an arbitrary IN
// byte stream, cut into transfers of arbitrary sizes as the FT232 would send them (2 modem
// status bytes at the head of every 64-byte USB packet), each transfer drained as a tick does.
// Checked: every frame begins '<' and ends '>'; every data byte is accounted for (in a frame,
// skipped, overflowed or still buffered); without overflow the frames are those an independent
// scan of the whole stream finds, in order; a frame that decodes re-encodes, as a command of its
// counts, to the same motor nibbles, and a refused one holds a byte out of its range.
//
// Input: byte 0 the seed of the transfer sizes, the rest the stream.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drivers/falcon/falcon_protocol.h"
#include "support/check.h"

namespace {

using hapticd::fuzz::require;
namespace fa = hapticd::drivers::falcon;

// The data of the transfers with the status bytes dropped, scanned at once.
std::vector<fa::Packet> model_frames(const std::vector<unsigned char>& data) {
  std::vector<fa::Packet> frames;
  std::size_t i = 0;
  while (i + fa::kPacketBytes <= data.size()) {
    if (data[i] == '<' && data[i + fa::kPacketBytes - 1] == '>') {
      fa::Packet p;
      for (std::size_t k = 0; k < fa::kPacketBytes; ++k) p[k] = data[i + k];
      frames.push_back(p);
      i += fa::kPacketBytes;
    } else {
      ++i;
    }
  }
  return frames;
}

void check_decode(const fa::Packet& p) {
  fa::State s;
  const fa::PacketError e = fa::decode_state(p, s);
  bool in_range = true;
  for (std::size_t i = 1; i < 15; ++i) {
    const unsigned hi = i == 13 ? 0x41 + 0x7F : 0x41 + 0xF;
    in_range = in_range && p[i] >= 0x41 && p[i] <= hi;
  }
  require((e == fa::PacketError::kNone) == in_range, "decoded exactly the packets in range");
  if (e != fa::PacketError::kNone) return;
  fa::Command c;
  c.motor = s.encoder;
  const fa::Packet again = fa::encode_command(c);
  for (std::size_t i = 1; i < 13; ++i) require(again[i] == p[i], "counts re-encode to the bytes");
  require(s.homed < 8 && s.grip < 16, "homing and grip bits in their fields");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::uint32_t seed = data[0];
  const std::span<const std::uint8_t> in(data + 1, size - 1);
  fa::PacketStream stream;
  std::vector<unsigned char> stripped;
  std::vector<fa::Packet> got;
  std::size_t at = 0;
  while (at < in.size()) {
    seed = seed * 1103515245u + 12345u;
    const std::size_t n = std::min<std::size_t>(1 + (seed >> 16) % 200, in.size() - at);
    const auto transfer = in.subspan(at, n);
    for (std::size_t k = 0; k < n; ++k) {
      if (k % fa::kUsbPacketBytes >= fa::kModemStatusBytes) stripped.push_back(transfer[k]);
    }
    stream.feed_transfer(transfer);
    fa::Packet p;
    while (stream.next(p)) {
      require(p[0] == '<' && p[fa::kPacketBytes - 1] == '>', "a frame is framed");
      check_decode(p);
      got.push_back(p);
    }
    at += n;
  }
  require(got.size() * fa::kPacketBytes + stream.skipped_bytes() + stream.overflowed_bytes() +
                  stream.buffered_bytes() ==
              stripped.size(),
          "every data byte accounted for");
  if (stream.overflowed_bytes() == 0) {
    require(got == model_frames(stripped), "the frames an independent scan finds");
  }
  return 0;
}
