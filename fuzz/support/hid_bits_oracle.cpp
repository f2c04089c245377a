#include "support/hid_bits_oracle.h"

#include <span>

#include "drivers/hid/report_descriptor.h"
#include "support/check.h"

namespace hapticd::fuzz {
namespace {

namespace hid = hapticd::drivers::hid;
using Bytes = std::vector<std::uint8_t>;

bool bit_at(std::span<const std::uint8_t> d, std::uint64_t bit) {
  return bit / 8 < d.size() && ((d[bit / 8] >> (bit % 8)) & 1u) != 0;
}

}  // namespace

Bytes put_bits_model(Bytes d, std::uint64_t offset, std::uint32_t bits, std::uint32_t value) {
  for (std::uint32_t i = 0; i < bits; ++i) {
    const std::uint64_t b = offset + i;
    if (b / 8 >= d.size()) break;
    const auto mask = static_cast<std::uint8_t>(1u << (b % 8));
    d[b / 8] =
        static_cast<std::uint8_t>(((value >> i) & 1u) != 0 ? d[b / 8] | mask : d[b / 8] & ~mask);
  }
  return d;
}

void check_hid_bits(HidInput& r) {
  const std::uint8_t flags = r.u8();
  const std::uint32_t offset = (flags & 1u) != 0 ? r.u32() : r.u16();
  const std::uint32_t bits = r.u8() % 33u;
  const std::uint32_t value = r.u32();
  const std::span<const std::uint8_t> tail = r.rest();
  Bytes data(tail.begin(), tail.end());  // its own allocation: ASan sees any overrun
  std::uint32_t want = 0;
  for (std::uint32_t i = 0; i < bits; ++i)
    want |= static_cast<std::uint32_t>(bit_at(data, std::uint64_t{offset} + i)) << i;
  const std::uint32_t got = hid::get_bits(data, offset, bits);
  require(got == want, "get_bits reads the bits in HID order, 0 past the data");
  const Bytes expect = put_bits_model(data, offset, bits, value);
  hid::put_bits(data, offset, bits, value);
  require(data == expect, "put_bits writes those bits only, and nothing past the data");
  const std::uint32_t mask = bits == 32 ? ~0u : (1u << bits) - 1u;
  if (std::uint64_t{offset} + bits <= 8 * std::uint64_t{data.size()}) {
    require(hid::get_bits(data, offset, bits) == (value & mask), "put_bits then get_bits");
  }
  const std::int64_t s = hid::field_value(got, bits, true);
  if (bits >= 1 && bits < 32) {
    const std::int64_t half = std::int64_t{1} << (bits - 1);
    require(s >= -half && s < half && (static_cast<std::uint32_t>(s) & mask) == got,
            "field_value sign-extends the field's own width");
  }
  require(hid::field_value(got, bits, false) == got, "field_value of an unsigned field");
}

}  // namespace hapticd::fuzz
