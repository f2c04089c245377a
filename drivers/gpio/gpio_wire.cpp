#include "drivers/gpio/gpio_wire.h"

namespace hapticd::drivers::gpio::wire {
namespace {

void put_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_u64(std::uint8_t* p, std::uint64_t v) noexcept {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint16_t get_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get_u32(const std::uint8_t* p) noexcept {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(p[i]) << (8 * i);
  return v;
}
std::uint64_t get_u64(const std::uint8_t* p) noexcept {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

bool all_zero(std::span<const std::uint8_t> bytes) noexcept {
  for (const std::uint8_t b : bytes) {
    if (b != 0) return false;
  }
  return true;
}

constexpr std::uint8_t kOutEnabled = 1u << 0;
constexpr std::uint8_t kOutDirection = 1u << 1;
constexpr std::uint8_t kOutInversed = 1u << 2;
constexpr std::uint8_t kAllLevels = kLevelA | kLevelB | kLevelIndex | kLevelFault;

}  // namespace

std::size_t encode_hello(std::span<std::uint8_t> out) noexcept {
  if (out.size() < kHelloSize) return 0;
  out[0] = static_cast<std::uint8_t>(Type::kHello);
  return kHelloSize;
}

std::size_t encode_output(const Output& o, std::span<std::uint8_t> out) noexcept {
  if (out.size() < kOutputSize) return 0;
  out[0] = static_cast<std::uint8_t>(Type::kOutput);
  out[1] = static_cast<std::uint8_t>((o.pwm_enabled ? kOutEnabled : 0) |
                                     (o.direction_level ? kOutDirection : 0) |
                                     (o.inversed ? kOutInversed : 0));
  out[2] = o.joint;
  out[3] = 0;
  put_u32(&out[4], 0);
  put_u64(&out[8], o.duty_ns);
  put_u64(&out[16], o.period_ns);
  return kOutputSize;
}

std::size_t encode_levels(const Levels& l, std::span<std::uint8_t> out) noexcept {
  const std::size_t size = kLevelsSize + l.joint_count - 1;
  if (l.joint_count == 0 || l.joint_count > kMaxJoints || out.size() < size) return 0;
  out[0] = static_cast<std::uint8_t>(Type::kLevels);
  out[1] = l.levels & kAllLevels;
  put_u64(&out[2], static_cast<std::uint64_t>(l.time_ns));
  for (std::size_t j = 1; j < l.joint_count; ++j) out[kLevelsSize + j - 1] = l.of(j) & kAllLevels;
  return size;
}

std::size_t encode_edges(std::int64_t complete_until_ns, std::span<const Edge> edges,
                         std::span<std::uint8_t> out) noexcept {
  const std::size_t size = kEdgesHeaderSize + edges.size() * kEdgeSize;
  if (edges.size() > kMaxEdgesPerMessage || out.size() < size) return 0;
  out[0] = static_cast<std::uint8_t>(Type::kEdges);
  out[1] = 0;
  put_u16(&out[2], static_cast<std::uint16_t>(edges.size()));
  put_u32(&out[4], 0);
  put_u64(&out[8], static_cast<std::uint64_t>(complete_until_ns));
  std::uint8_t* p = &out[kEdgesHeaderSize];
  for (const Edge& e : edges) {
    put_u64(p, static_cast<std::uint64_t>(e.time_ns));
    put_u32(p + 8, e.seqno);
    p[12] = static_cast<std::uint8_t>(static_cast<unsigned>(e.line) | (e.joint << 4));
    p[13] = e.level ? 1 : 0;
    p += kEdgeSize;
  }
  return size;
}

bool peek_type(std::span<const std::uint8_t> msg, Type& type) noexcept {
  if (msg.empty()) return false;
  const std::uint8_t t = msg[0];
  if (t < static_cast<std::uint8_t>(Type::kHello) || t > static_cast<std::uint8_t>(Type::kEdges)) {
    return false;
  }
  type = static_cast<Type>(t);
  return true;
}

bool decode_hello(std::span<const std::uint8_t> msg) noexcept {
  return msg.size() == kHelloSize && msg[0] == static_cast<std::uint8_t>(Type::kHello);
}

bool decode_output(std::span<const std::uint8_t> msg, Output& o) noexcept {
  if (msg.size() != kOutputSize || msg[0] != static_cast<std::uint8_t>(Type::kOutput)) return false;
  if ((msg[1] & ~(kOutEnabled | kOutDirection | kOutInversed)) != 0) return false;
  if (msg[2] >= kMaxJoints) return false;
  if (!all_zero(msg.subspan(3, 5))) return false;  // reserved: a sender that sets them is wrong
  const std::uint64_t duty = get_u64(&msg[8]);
  const std::uint64_t period = get_u64(&msg[16]);
  if (duty > period) return false;  // the PWM core refuses it too
  o.joint = msg[2];
  o.pwm_enabled = (msg[1] & kOutEnabled) != 0;
  o.direction_level = (msg[1] & kOutDirection) != 0;
  o.inversed = (msg[1] & kOutInversed) != 0;
  o.duty_ns = duty;
  o.period_ns = period;
  return true;
}

bool decode_levels(std::span<const std::uint8_t> msg, Levels& l) noexcept {
  if (msg.size() < kLevelsSize || msg.size() > kLevelsSize + kMaxJoints - 1 ||
      msg[0] != static_cast<std::uint8_t>(Type::kLevels)) {
    return false;
  }
  for (std::size_t i = kLevelsSize; i < msg.size(); ++i) {
    if ((msg[i] & ~kAllLevels) != 0) return false;
  }
  if ((msg[1] & ~kAllLevels) != 0) return false;
  l.levels = msg[1];
  l.time_ns = static_cast<std::int64_t>(get_u64(&msg[2]));
  l.joint_count = 1 + msg.size() - kLevelsSize;
  for (std::size_t j = 1; j < l.joint_count; ++j) l.others[j - 1] = msg[kLevelsSize + j - 1];
  return true;
}

bool decode_edges_header(std::span<const std::uint8_t> msg, EdgesHeader& h) noexcept {
  if (msg.size() < kEdgesHeaderSize || msg[0] != static_cast<std::uint8_t>(Type::kEdges)) {
    return false;
  }
  if (msg[1] != 0 || !all_zero(msg.subspan(4, 4))) return false;  // reserved
  const std::uint16_t count = get_u16(&msg[2]);
  if (count > kMaxEdgesPerMessage || msg.size() != kEdgesHeaderSize + count * kEdgeSize) {
    return false;
  }
  h.count = count;
  h.complete_until_ns = static_cast<std::int64_t>(get_u64(&msg[8]));
  return true;
}

bool decode_edge(std::span<const std::uint8_t> msg, std::size_t i, Edge& e) noexcept {
  const std::size_t at = kEdgesHeaderSize + i * kEdgeSize;
  if (i >= kMaxEdgesPerMessage || at + kEdgeSize > msg.size()) return false;
  const std::uint8_t* p = &msg[at];
  const unsigned line = p[12] & 0x0Fu;
  const unsigned joint = p[12] >> 4;
  if (line >= kLineCount || joint >= kMaxJoints || p[13] > 1) return false;
  e.time_ns = static_cast<std::int64_t>(get_u64(p));
  e.seqno = get_u32(p + 8);
  e.line = static_cast<Line>(line);
  e.joint = static_cast<std::uint8_t>(joint);
  e.level = p[13] != 0;
  return true;
}

}  // namespace hapticd::drivers::gpio::wire
