#include "drivers/evdev/evdev_wire.h"

#include <cstring>

namespace hapticd::drivers::evdev::wire {
namespace {

// Little-endian writer into a fixed buffer (the RT encoders) or a vector.
struct Writer {
  std::uint8_t* p;
  void u8(std::uint32_t v) { *p++ = static_cast<std::uint8_t>(v); }
  void u16(std::uint32_t v) {
    u8(v & 0xFF);
    u8((v >> 8) & 0xFF);
  }
  void u32(std::uint32_t v) {
    u16(v & 0xFFFF);
    u16(v >> 16);
  }
  void u64(std::uint64_t v) {
    u32(static_cast<std::uint32_t>(v));
    u32(static_cast<std::uint32_t>(v >> 32));
  }
};

class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> b) : b_(b) {}
  bool ok() const { return ok_; }
  bool at_end() const { return pos_ == b_.size(); }
  std::uint32_t u8() { return take(1) ? b_[pos_ - 1] : 0u; }
  std::uint32_t u16() { return u8() | (u8() << 8); }
  std::uint32_t u32() { return u16() | (u16() << 16); }
  std::uint64_t u64() {
    const std::uint64_t lo = u32();
    return lo | (std::uint64_t{u32()} << 32);
  }
  void fail() { ok_ = false; }
  std::string text() {
    const std::size_t n = u8();
    if (!take(n)) return {};
    return std::string(reinterpret_cast<const char*>(b_.data() + pos_ - n), n);
  }

 private:
  bool take(std::size_t n) {
    if (!ok_ || b_.size() - pos_ < n) {
      ok_ = false;
      return false;
    }
    pos_ += n;
    return true;
  }
  std::span<const std::uint8_t> b_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

void put_text(std::vector<std::uint8_t>& out, const std::string& s) {
  const std::size_t n = s.size() > 255 ? 255 : s.size();
  out.push_back(static_cast<std::uint8_t>(n));
  out.insert(out.end(), s.begin(), s.begin() + static_cast<std::ptrdiff_t>(n));
}

std::size_t encode_fixed(const Message& m, std::uint8_t* buf) {
  Writer w{buf};
  w.u8(static_cast<std::uint8_t>(m.type));
  switch (m.type) {
    case Type::kEvent:
      w.u16(m.event.type);
      w.u16(m.event.code);
      w.u32(static_cast<std::uint32_t>(m.event.value));
      w.u64(static_cast<std::uint64_t>(m.event.time_ns));
      break;
    case Type::kUpload:
      w.u16(static_cast<std::uint16_t>(m.effect.id));
      w.u16(m.effect.direction);
      w.u16(static_cast<std::uint16_t>(m.effect.level));
      w.u16(m.effect.length_ms);
      break;
    case Type::kWriteFf:
    case Type::kStatus:
      w.u32(static_cast<std::uint32_t>(m.a));
      w.u32(static_cast<std::uint32_t>(m.b));
      w.u32(static_cast<std::uint32_t>(m.error));
      break;
    case Type::kQuery:
    case Type::kGrab:
    case Type::kErase:
      w.u32(static_cast<std::uint32_t>(m.a));
      break;
    case Type::kFacts:
      break;  // variable length: encode() adds it
    case Type::kAnswers:
      break;  // the descriptor travels beside the bytes
  }
  return static_cast<std::size_t>(w.p - buf);
}

void encode_facts(const Facts& f, std::vector<std::uint8_t>& out) {
  std::uint8_t fixed[48];
  Writer w{fixed};
  for (std::uint32_t v : {std::uint32_t{f.bus}, std::uint32_t{f.vendor}, std::uint32_t{f.product},
                          std::uint32_t{f.version}}) {
    w.u16(v);
  }
  w.u8((f.has_axis ? 1u : 0u) | (f.ff_constant ? 2u : 0u) | (f.ff_gain ? 4u : 0u) |
       (f.ff_autocenter ? 8u : 0u));
  for (std::int32_t v :
       {f.range.minimum, f.range.maximum, f.range.resolution, f.value, f.fuzz, f.ff_effects}) {
    w.u32(static_cast<std::uint32_t>(v));
  }
  out.insert(out.end(), fixed, w.p);
  put_text(out, f.name);
  put_text(out, f.phys);
  put_text(out, f.uniq);
}

Facts decode_facts(Reader& r) {
  Facts f;
  f.bus = static_cast<std::uint16_t>(r.u16());
  f.vendor = static_cast<std::uint16_t>(r.u16());
  f.product = static_cast<std::uint16_t>(r.u16());
  f.version = static_cast<std::uint16_t>(r.u16());
  const std::uint32_t flags = r.u8();
  if ((flags & ~0xFu) != 0) r.fail();  // one encoding per message: no bit that means nothing
  f.has_axis = flags & 1u;
  f.ff_constant = flags & 2u;
  f.ff_gain = flags & 4u;
  f.ff_autocenter = flags & 8u;
  f.range.minimum = static_cast<std::int32_t>(r.u32());
  f.range.maximum = static_cast<std::int32_t>(r.u32());
  f.range.resolution = static_cast<std::int32_t>(r.u32());
  f.value = static_cast<std::int32_t>(r.u32());
  f.fuzz = static_cast<std::int32_t>(r.u32());
  f.ff_effects = static_cast<std::int32_t>(r.u32());
  f.name = r.text();
  f.phys = r.text();
  f.uniq = r.text();
  return f;
}

}  // namespace

void encode(const Message& m, std::vector<std::uint8_t>& out) {
  out.clear();
  std::uint8_t fixed[32];
  const std::size_t n = encode_fixed(m, fixed);
  out.insert(out.end(), fixed, fixed + n);
  if (m.type == Type::kFacts) encode_facts(m.facts, out);
}

std::optional<Message> decode(std::span<const std::uint8_t> bytes) {
  if (bytes.empty() || bytes.size() > kMaxMessage) return std::nullopt;
  Reader r(bytes);
  Message m;
  const std::uint32_t type = r.u8();
  if (type < static_cast<std::uint32_t>(Type::kEvent) ||
      type > static_cast<std::uint32_t>(Type::kAnswers)) {
    return std::nullopt;
  }
  m.type = static_cast<Type>(type);
  switch (m.type) {
    case Type::kEvent:
      m.event.type = static_cast<std::uint16_t>(r.u16());
      m.event.code = static_cast<std::uint16_t>(r.u16());
      m.event.value = static_cast<std::int32_t>(r.u32());
      m.event.time_ns = static_cast<std::int64_t>(r.u64());
      break;
    case Type::kUpload:
      m.effect.id = static_cast<std::int16_t>(r.u16());
      m.effect.direction = static_cast<std::uint16_t>(r.u16());
      m.effect.level = static_cast<std::int16_t>(r.u16());
      m.effect.length_ms = static_cast<std::uint16_t>(r.u16());
      break;
    case Type::kWriteFf:
    case Type::kStatus:
      m.a = static_cast<std::int32_t>(r.u32());
      m.b = static_cast<std::int32_t>(r.u32());
      m.error = static_cast<std::int32_t>(r.u32());
      break;
    case Type::kQuery:
    case Type::kGrab:
    case Type::kErase:
      m.a = static_cast<std::int32_t>(r.u32());
      break;
    case Type::kFacts:
      m.facts = decode_facts(r);
      break;
    case Type::kAnswers:
      break;
  }
  if (!r.ok() || !r.at_end()) return std::nullopt;
  return m;
}

std::size_t encode_event(const Event& e, std::span<std::uint8_t> out) noexcept {
  Message m;
  m.type = Type::kEvent;
  m.event = e;
  return encode_fixed(m, out.data());
}

std::size_t encode_upload(const Effect& e, std::span<std::uint8_t> out) noexcept {
  Message m;
  m.type = Type::kUpload;
  m.effect = e;
  return encode_fixed(m, out.data());
}

std::size_t encode_write_ff(int code, int value, std::span<std::uint8_t> out) noexcept {
  Message m;
  m.type = Type::kWriteFf;
  m.a = code;
  m.b = value;
  return encode_fixed(m, out.data());
}

}  // namespace hapticd::drivers::evdev::wire
