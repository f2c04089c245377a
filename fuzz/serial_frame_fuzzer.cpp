// libFuzzer target for the serial driver's pure codecs: an arbitrary byte stream, cut into
// pieces of arbitrary sizes, through the FrameScanner of one of four frame layouts (CRC-16
// with two sync bytes, Haply's one id byte and no check, a sum8 and a CRC-8 with a check in
// the middle of the frame). Checked against an independent model that scans the whole stream
// at once: the same frames in the same order, each starting with its sync and passing its
// check, and every byte accounted for (in a frame, skipped, or the unfinished tail). Then each
// frame's decoded positions re-encoded: the frame hapticd would send passes its own check.
//
// Input: byte 0 the layout (mod 4), byte 1 the seed of the piece sizes, the rest the stream.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "drivers/serial/serial_frame.h"
#include "support/check.h"

namespace {

using hapticd::fuzz::require;
namespace s = hapticd::drivers::serial;
namespace f = hapticd::drivers::field;

std::vector<s::InputLayout> layouts() {
  std::vector<s::InputLayout> v(4);
  v[0].shape = {
      {0xA5, 0x5A},
      14,
      s::FrameCheck{s::find_check_algorithm("crc-16/ibm-3740"), 12, 2, 12, f::Endian::kBig}};
  v[0].positions = {f::typed(f::FieldType::kI24, 3, f::Endian::kBig, 1e-3)};
  v[1].shape = {{0x05}, 9, std::nullopt};
  v[1].positions = {f::typed(f::FieldType::kF32, 1), f::typed(f::FieldType::kF32, 5)};
  v[2].shape = {
      {0x7E}, 6, s::FrameCheck{s::find_check_algorithm("sum8"), 5, 1, 5, f::Endian::kLittle}};
  v[2].positions = {f::FieldSpec{1, 4, 12, true, false, f::Endian::kLittle, 1e-4, 0.0}};
  v[3].shape = {
      {0xAA, 0x55, 0x01},
      11,
      s::FrameCheck{s::find_check_algorithm("crc-8/maxim-dow"), 3, 4, 11, f::Endian::kLittle}};
  v[3].positions = {f::typed(f::FieldType::kU16, 4),
                    f::typed(f::FieldType::kI32, 6, f::Endian::kBig)};
  return v;
}

// The model: every frame of the whole stream, scanning from its first byte.
std::vector<std::size_t> model_frames(const s::FrameShape& shape,
                                      std::span<const std::uint8_t> in) {
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < in.size();) {
    const bool sync = i + shape.sync.size() <= in.size() &&
                      std::equal(shape.sync.begin(), shape.sync.end(),
                                 in.begin() + static_cast<std::ptrdiff_t>(i));
    if (sync && i + shape.length <= in.size() && s::check_ok(shape, in.subspan(i, shape.length))) {
      at.push_back(i);
      i += shape.length;
    } else {
      ++i;
    }
  }
  return at;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  static const std::vector<s::InputLayout> kLayouts = layouts();
  const s::InputLayout& layout = kLayouts[data[0] % kLayouts.size()];
  std::uint32_t seed = data[1];
  const std::span<const std::uint8_t> stream(data + 2, size - 2);
  const std::vector<std::size_t> expected = model_frames(layout.shape, stream);

  s::FrameScanner scanner(layout.shape);
  std::size_t found = 0;
  for (std::size_t at = 0; at < stream.size();) {
    seed = seed * 1103515245u + 12345u;
    const std::size_t n = std::min<std::size_t>(1 + (seed >> 16) % 97, stream.size() - at);
    scanner.push(stream.subspan(at, n));
    at += n;
    for (auto frame = scanner.next(); !frame.empty(); frame = scanner.next()) {
      require(found < expected.size(), "no frame the whole-stream scan does not find");
      require(frame.size() == layout.shape.length &&
                  std::memcmp(frame.data(), stream.data() + expected[found], frame.size()) == 0,
              "the same frames in the same order as the whole-stream scan");
      require(s::check_ok(layout.shape, frame), "every frame passes its check");
      s::InputValues v;
      s::decode_input(frame, layout, v);
      std::array<std::uint8_t, s::kMaxFrame> out{};
      s::OutputLayout o;
      o.shape = layout.shape;
      o.forces = layout.positions;
      s::encode_output(std::span<const double>(v.position.data(), layout.positions.size()), true, o,
                       out);
      require(s::check_ok(o.shape, std::span(out).first(o.shape.length)),
              "a frame hapticd encodes passes its own check");
      ++found;
    }
  }
  require(found == expected.size(), "every frame the whole-stream scan finds");
  const s::ScanCounts& c = scanner.counts();
  require(c.overflowed == 0, "pieces this small never overflow");
  const std::uint64_t used = c.frames * layout.shape.length + c.skipped + c.bad_check;
  require(used <= stream.size() && stream.size() - used < layout.shape.length,
          "every byte in a frame, skipped, or in the unfinished tail");
  return 0;
}
