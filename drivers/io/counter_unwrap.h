// A counter narrower than the loop's position, followed from one reading to the next: a
// position field that wraps modulo 2^bits on a multi-turn axis (a u16 or i16 of a vendor HID
// report, CiA 402's 32-bit Position Actual Value). The motion between two readings is taken the
// short way round, so the count goes on past the field's ends as the axis does, and the loop's
// speed check judges the real motion. A move of half the field's range or more between two
// readings cannot be told from one the other way: a field that wraps must span more than twice
// the largest move a sample period allows (safety.max_speed x T), which the driver that uses
// this checks at configuration. Pure: no OS header, shared by every driver.
#pragma once

#include <cstdint>

namespace hapticd::io {

// RT-safe. The step from reading `previous` to reading `current` of a counter modulo 2^bits
// (bits 1..63; the readings signed or not, only their low bits count): the representative of
// (current - previous) mod 2^bits in [-2^(bits-1), 2^(bits-1)).
constexpr std::int64_t wrapped_step(std::int64_t previous, std::int64_t current,
                                    unsigned bits) noexcept {
  const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
  const std::uint64_t half = std::uint64_t{1} << (bits - 1);
  const std::uint64_t d =
      (static_cast<std::uint64_t>(current) - static_cast<std::uint64_t>(previous)) & mask;
  return d >= half ? -static_cast<std::int64_t>(mask - d) - 1 : static_cast<std::int64_t>(d);
}

class CounterUnwrap {
 public:
  explicit constexpr CounterUnwrap(unsigned bits = 32) noexcept : bits_(bits) {}

  // RT-safe. The unwrapped count after reading `raw`: the first reading as it is (its value
  // decides which turn the axis is on), each later one the last count plus the step to it.
  constexpr std::int64_t update(std::int64_t raw) noexcept {
    count_ = started_ ? count_ + wrapped_step(last_, raw, bits_) : raw;
    last_ = raw;
    started_ = true;
    return count_;
  }
  // The next reading starts again from its own value (a new session with the device).
  constexpr void reset() noexcept { started_ = false; }
  constexpr std::int64_t count() const noexcept { return count_; }
  constexpr unsigned bits() const noexcept { return bits_; }

 private:
  unsigned bits_;
  bool started_ = false;
  std::int64_t last_ = 0, count_ = 0;
};

}  // namespace hapticd::io
