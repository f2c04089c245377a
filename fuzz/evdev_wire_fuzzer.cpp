// libFuzzer target for the evdev driver's loopback framing (drivers/evdev/evdev_wire.h), what
// the driver and its simulated device read from each other: any bytes either decode to a
// message or are refused, never read past the end; an accepted message re-encodes to exactly
// the bytes it came from (the format has one encoding per message), and the fixed-size
// encoders the RT path uses agree with the general one. Then the level and axis arithmetic on
// numbers taken from the input: a level is always within +-0x7fff, an axis position finite.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_wire.h"
#include "support/check.h"

namespace {

using hapticd::fuzz::require;
namespace ev = hapticd::drivers::evdev;

void check_fixed(const ev::wire::Message& m) {
  std::array<std::uint8_t, 32> fixed{};
  std::size_t n = 0;
  if (m.type == ev::wire::Type::kEvent) n = ev::wire::encode_event(m.event, fixed);
  if (m.type == ev::wire::Type::kUpload) n = ev::wire::encode_upload(m.effect, fixed);
  if (n == 0) return;
  std::vector<std::uint8_t> general;
  ev::wire::encode(m, general);
  require(general.size() == n && std::memcmp(general.data(), fixed.data(), n) == 0,
          "the RT encoder differs from the general one");
}

void check_arithmetic(const std::uint8_t* data, std::size_t size) {
  if (size < 16) return;
  double force = 0.0, scale = 0.0;
  std::memcpy(&force, data, 8);
  std::memcpy(&scale, data + 8, 8);
  if (std::isfinite(scale) && scale > 0.0) {
    const int level = ev::force_level(force, scale);
    require(level >= -ev::kLevelMax && level <= ev::kLevelMax, "a level past +-0x7fff");
  }
  if (size < 28) return;
  std::int32_t value = 0, lo = 0, hi = 0;
  std::memcpy(&value, data + 16, 4);
  std::memcpy(&lo, data + 20, 4);
  std::memcpy(&hi, data + 24, 4);
  if (hi <= lo) return;
  const ev::AxisSettings axis{0, ev::Scale::kRange, -1.0, 1.0, false, 0.0};
  require(std::isfinite(ev::axis_position(value, axis, {lo, hi, 0})), "a non-finite position");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  if (const auto m = ev::wire::decode(bytes)) {
    std::vector<std::uint8_t> again;
    ev::wire::encode(*m, again);
    require(again.size() == size && std::memcmp(again.data(), data, size) == 0,
            "an accepted message does not re-encode to its bytes");
    check_fixed(*m);
  }
  check_arithmetic(data, size);
  return 0;
}
