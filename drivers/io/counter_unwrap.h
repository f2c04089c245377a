// A position counter narrower than the loop's position, unwrapped: a drive's 32-bit position
// actual (CiA 402 0x6064), a report field of 16 bits. Such a counter passes its largest value
// and continues at its smallest (a multi-turn axis, a fine encoder, a drive that keeps an
// offset); taken as it is, the rollover is a jump of the whole range, which the loop's speed
// check rightly faults on. Masters keep their own position instead, from the difference of
// successive raw values modulo the counter's width (RMP's note "Signed 32-bit Motor Position
// Overflow/Underflow"): a difference is taken as the shortest way round, so any motion of less
// than half the range between two samples is followed exactly, across the wrap in either
// direction.
//
// The first sample after reset() sets the base: the position is the raw value itself (sign-
// extended for a signed counter), so a counter that has not wrapped reads as it always did.
// A re-enable does not reset it: the next sample continues from the last one.
#pragma once

#include <cstdint>

namespace hapticd::io {

class CounterUnwrap {
 public:
  // `bits`: the counter's width, 1..64; `is_signed`: its values are two's complement (the
  // base of the first sample; the differences are the same either way).
  constexpr CounterUnwrap(int bits, bool is_signed) noexcept
      : mask_(bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1),
        half_(bits >= 64 ? std::uint64_t{1} << 63 : std::uint64_t{1} << (bits - 1)),
        signed_(is_signed) {}

  // RT-safe: called every tick. The unwrapped position for the counter's raw value (only its
  // low `bits` are read: a sign-extended or a zero-extended value gives the same).
  constexpr std::int64_t next(std::uint64_t raw) noexcept {
    raw &= mask_;
    if (!started_) {
      started_ = true;
      value_ = extend(raw);
    } else {
      value_ += difference(raw, last_);
    }
    last_ = raw;
    return value_;
  }

  // RT-safe. The next raw value sets the base again (at configure: a new session).
  constexpr void reset() noexcept { started_ = false; }
  constexpr bool started() const noexcept { return started_; }
  // RT-safe. The last position next() returned.
  constexpr std::int64_t value() const noexcept { return value_; }

  // RT-safe. raw - previous modulo 2^bits, the shortest way round: in [-2^(bits-1),
  // 2^(bits-1)).
  constexpr std::int64_t difference(std::uint64_t raw, std::uint64_t previous) const noexcept {
    const std::uint64_t d = (raw - previous) & mask_;
    // In [2^(bits-1), 2^bits): the other way round, d - 2^bits (two's complement in 64 bits).
    return static_cast<std::int64_t>(d >= half_ ? d - mask_ - 1 : d);
  }

 private:
  constexpr std::int64_t extend(std::uint64_t raw) const noexcept {
    return static_cast<std::int64_t>(signed_ && raw >= half_ ? raw - mask_ - 1 : raw);
  }

  std::uint64_t mask_;
  std::uint64_t half_;
  bool signed_;
  bool started_ = false;
  std::uint64_t last_ = 0;
  std::int64_t value_ = 0;
};

}  // namespace hapticd::io
