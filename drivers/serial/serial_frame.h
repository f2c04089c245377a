// The serial driver's frames (docs/drivers/serial.md): fixed-length frames that start with
// sync bytes, carry numeric fields anywhere (drivers/field/field.h: any byte, bit, width and
// byte order, floats) and may end in a check (checksum.h), described by the configuration as
// HID vendor reports are. The device sends input frames (one position per joint, optionally a
// sequence counter and status bits); hapticd sends output frames (one force per joint,
// optionally an enable switch). The driver and its loopback peer share these codecs. Pure: no
// OS header; the RT functions never allocate.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "base/joints.h"
#include "drivers/field/field.h"
#include "drivers/serial/checksum.h"

namespace hapticd::drivers::serial {

using field::FieldSpec;

// Longest frame the driver takes: larger than any device's state, small enough to live on the
// stack of the RT thread.
inline constexpr std::size_t kMaxFrame = 256;
inline constexpr std::size_t kMaxSync = 8;

// Where a frame's check sits and what it covers: bytes [from, to) checked, stored at `at`
// (a CRC-16 in `endian` order).
struct FrameCheck {
  const CheckAlgorithm* algorithm = nullptr;
  std::size_t at = 0;
  std::size_t from = 0;
  std::size_t to = 0;
  field::Endian endian = field::Endian::kBig;
};

struct FrameShape {
  std::vector<std::uint8_t> sync;  // the bytes every frame starts with (may be empty: output)
  std::size_t length = 0;          // the whole frame, sync and check included
  std::optional<FrameCheck> check;
};

struct InputLayout {
  FrameShape shape;
  std::vector<FieldSpec> positions;   // one per joint (m or rad)
  std::optional<FieldSpec> sequence;  // the device's frame counter (unsigned integer)
  std::optional<FieldSpec> status;    // status bits (integer)
  std::uint32_t fault_mask = 0;       // status bits that mean the device faulted
};

struct EnableField {
  FieldSpec field;
  double on = 1.0;
  double off = 0.0;
};

struct OutputLayout {
  FrameShape shape;
  std::vector<FieldSpec> forces;  // one per joint (N or N m); scale is N per count
  std::optional<EnableField> enable;
};

// Not RT-safe. Everything wrong with a frame's layout, "<where>: <what>", <where> a key path
// below device.serial ("input.positions[1]", "output.check"): fields past the frame or over
// the sync or the check, a check outside the frame, a sync longer than the frame.
std::vector<std::string> validate(const InputLayout& in, const std::string& where);
std::vector<std::string> validate(const OutputLayout& out, const std::string& where);

// RT-safe. Whether `frame` (shape.length bytes) carries the right check; true without one.
bool check_ok(const FrameShape& shape, std::span<const std::uint8_t> frame) noexcept;
// RT-safe. Writes the check of `frame` into it, once its other bytes are written.
void seal(const FrameShape& shape, std::span<std::uint8_t> frame) noexcept;

struct InputValues {
  std::array<double, base::kMaxJoints> position{};
  std::uint32_t sequence = 0;
  std::uint32_t status = 0;
};

// RT-safe: called every tick. The values of a whole, checked input frame.
void decode_input(std::span<const std::uint8_t> frame, const InputLayout& layout,
                  InputValues& out) noexcept;
// RT-safe. The peer's side: a whole input frame, sync and check included.
void encode_input(const InputValues& in, const InputLayout& layout,
                  std::span<std::uint8_t> frame) noexcept;

// RT-safe: called every tick. A whole output frame: sync, each joint's force (rounded, clamped
// to its field), the enable switch, the check.
void encode_output(std::span<const double> forces, bool enable, const OutputLayout& layout,
                   std::span<std::uint8_t> frame) noexcept;
struct OutputValues {
  std::array<double, base::kMaxJoints> force{};
  bool enable = true;  // true when the layout has no enable field
};
// RT-safe. The peer's side: a whole, checked output frame.
void decode_output(std::span<const std::uint8_t> frame, const OutputLayout& layout,
                   OutputValues& out) noexcept;

// What finding frames in a byte stream met, counted since construction.
struct ScanCounts {
  std::uint64_t frames = 0;      // whole frames with a good check
  std::uint64_t bad_check = 0;   // sync and length right, check wrong: one byte skipped
  std::uint64_t skipped = 0;     // bytes that started no frame (noise, a frame cut short)
  std::uint64_t overflowed = 0;  // bytes dropped because more arrived than the buffer holds
};

// Finds frames of one shape in a byte stream as it arrives in pieces: a frame starts at its
// sync bytes and is `length` long; a frame whose check fails gives up its first byte and the
// hunt goes on from the next, so a sync pattern inside a payload costs one lost frame, never
// the stream. No allocation after construction.
class FrameScanner {
 public:
  explicit FrameScanner(const FrameShape& shape) noexcept : shape_(&shape) {}

  // RT-safe: called every tick. Appends received bytes.
  void push(std::span<const std::uint8_t> bytes) noexcept;
  // RT-safe: called every tick. The next whole, checked frame, or an empty span when none is
  // complete yet. The span is valid until the next push() or next().
  std::span<const std::uint8_t> next() noexcept;
  const ScanCounts& counts() const noexcept { return counts_; }
  void clear() noexcept { size_ = start_ = 0; }

 private:
  void compact() noexcept;
  const FrameShape* shape_;
  // Twice what one read takes (serial_device.h), so a read never pushes out a frame begun.
  std::array<std::uint8_t, 8 * kMaxFrame> buf_{};
  std::size_t start_ = 0;  // the first byte not yet consumed
  std::size_t size_ = 0;   // bytes held, from 0
  ScanCounts counts_;
};

}  // namespace hapticd::drivers::serial
