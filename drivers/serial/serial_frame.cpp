#include "drivers/serial/serial_frame.h"

#include "config/schema_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hapticd::drivers::serial {
namespace {

// Which bits of each byte of a frame something already uses, for overlap messages.
class Occupancy {
 public:
  explicit Occupancy(std::size_t length) : used_(length, 0), what_(length) {}
  // Marks `bits` of byte k as `name`'s; the name of what had them already, or empty.
  std::string claim(std::size_t k, std::uint8_t bits, const std::string& name) {
    if (k >= used_.size()) return {};
    if ((used_[k] & bits) != 0) return what_[k];
    used_[k] = static_cast<std::uint8_t>(used_[k] | bits);
    what_[k] = name;
    return {};
  }

 private:
  std::vector<std::uint8_t> used_;
  std::vector<std::string> what_;
};

void check_shape(const FrameShape& s, const std::string& where, Occupancy& occ,
                 std::vector<std::string>& errors) {
  if (s.length < 1 || s.length > kMaxFrame) {
    errors.push_back(where + ".length: " + std::to_string(s.length) + " bytes; a frame is 1 to " +
                     std::to_string(kMaxFrame));
    return;
  }
  if (s.sync.size() > kMaxSync || s.sync.size() >= s.length) {
    errors.push_back(where + ".sync: " + std::to_string(s.sync.size()) + " bytes; at most " +
                     std::to_string(kMaxSync) + " and fewer than length");
  }
  for (std::size_t k = 0; k < s.sync.size(); ++k) occ.claim(k, 0xFF, "sync");
  if (!s.check) return;
  const FrameCheck& c = *s.check;
  const std::size_t size = c.algorithm->size();
  if (c.at + size > s.length) {
    errors.push_back(where + ".check.byte: the check's " + std::to_string(size) + " byte(s) at " +
                     std::to_string(c.at) + " run past the frame's " + std::to_string(s.length));
  } else if (c.from >= c.to || c.to > s.length) {
    errors.push_back(where + ".check: covers bytes [" + std::to_string(c.from) + ", " +
                     std::to_string(c.to) + "), not a range inside the frame");
  } else if (c.at < c.to && c.at + size > c.from) {
    errors.push_back(where + ".check: the bytes it covers include the check itself");
  } else {
    for (std::size_t k = c.at; k < c.at + size; ++k) {
      if (const std::string o = occ.claim(k, 0xFF, "check"); !o.empty()) {
        errors.push_back(where + ".check.byte: byte " + std::to_string(k) + " is also " + o + "'s");
      }
    }
  }
}

void check_field(const FieldSpec& f, const std::string& name, const std::string& where,
                 std::size_t length, Occupancy& occ, std::vector<std::string>& errors) {
  if (f.end() > length) {
    errors.push_back(where + "." + name + ": ends at byte " + std::to_string(f.end()) +
                     ", past the frame's " + std::to_string(length));
    return;
  }
  for (std::size_t k = f.byte; k < f.end(); ++k) {
    if (const std::string o = occ.claim(k, f.mask_of_byte(k), name); !o.empty()) {
      errors.push_back(where + "." + name + ": byte " + std::to_string(k) + " is also " + o + "'s");
      return;
    }
  }
}

std::string indexed(const char* name, std::size_t i) {
  return std::string(name) + "[" + std::to_string(i) + "]";
}

// A check that leaves a field out lets a damaged value of it through.
void check_covers(const FrameShape& s, const FieldSpec& f, const std::string& name,
                  const std::string& where, std::vector<std::string>& errors) {
  if (!s.check || (f.byte >= s.check->from && f.end() <= s.check->to)) return;
  errors.push_back(where + ".check: covers bytes [" + std::to_string(s.check->from) + ", " +
                   std::to_string(s.check->to) + "), not all of " + name + " (bytes " +
                   std::to_string(f.byte) + ".." + std::to_string(f.end() - 1) + "): a damaged " +
                   name + " would pass it");
}

// The on and off values a switch writes: distinct, and what the field holds exactly.
void check_switch(const EnableField& e, const std::string& where,
                  std::vector<std::string>& errors) {
  for (const auto& [v, key] : {std::pair{e.on, ".on"}, {e.off, ".off"}}) {
    const bool exact =
        e.field.is_float ||
        (std::nearbyint(v) == v && v >= field::raw_min(e.field) && v <= field::raw_max(e.field));
    if (!exact) {
      errors.push_back(where + ".enable" + key + ": " + config::schema::format_number(v) +
                       " is no value the " + field::type_name(e.field) + " field holds");
    }
  }
  if (e.on == e.off) errors.push_back(where + ".enable: on and off are the same value");
}

}  // namespace

std::vector<std::string> validate(const InputLayout& in, const std::string& where) {
  std::vector<std::string> errors;
  Occupancy occ(in.shape.length);
  check_shape(in.shape, where, occ, errors);
  if (!errors.empty()) return errors;
  for (std::size_t i = 0; i < in.positions.size(); ++i) {
    check_field(in.positions[i], indexed("positions", i), where, in.shape.length, occ, errors);
  }
  for (const auto& [f, name] : {std::pair{&in.sequence, "sequence"}, {&in.status, "status"}}) {
    if (!*f) continue;
    if ((*f)->is_float || (*f)->is_signed) {
      errors.push_back(where + "." + name + ": an unsigned integer field (a u8, u16, bits: N)");
    }
    check_field(**f, name, where, in.shape.length, occ, errors);
    check_covers(in.shape, **f, name, where, errors);
  }
  for (std::size_t i = 0; i < in.positions.size(); ++i) {
    check_covers(in.shape, in.positions[i], indexed("positions", i), where, errors);
  }
  if (in.shape.sync.empty() && !in.shape.check) {
    errors.push_back(where +
                     ".sync: a frame with neither sync bytes nor a check is never found "
                     "again once a byte is lost: give its first byte(s) as sync");
  }
  if (in.fault_mask != 0 && !in.status) {
    errors.push_back(where + ".fault_mask: without a status field it can never fault");
  } else if (in.status && in.status->bits < 32 && (in.fault_mask >> in.status->bits) != 0) {
    errors.push_back(where + ".fault_mask: has bits beyond the status field's " +
                     std::to_string(in.status->bits));
  }
  return errors;
}

std::vector<std::string> validate(const OutputLayout& out, const std::string& where) {
  std::vector<std::string> errors;
  Occupancy occ(out.shape.length);
  check_shape(out.shape, where, occ, errors);
  if (!errors.empty()) return errors;
  for (std::size_t i = 0; i < out.forces.size(); ++i) {
    check_field(out.forces[i], indexed("forces", i), where, out.shape.length, occ, errors);
    check_covers(out.shape, out.forces[i], indexed("forces", i), where, errors);
    if (out.forces[i].offset != 0.0) {
      errors.push_back(where + "." + indexed("forces", i) +
                       ".offset: a force field takes none (zero force is raw 0, and the field's "
                       "reach and the force's reversal are its scale's)");
    }
  }
  if (out.enable) {
    check_field(out.enable->field, "enable", where, out.shape.length, occ, errors);
    check_covers(out.shape, out.enable->field, "enable", where, errors);
    check_switch(*out.enable, where, errors);
  }
  return errors;
}

bool check_ok(const FrameShape& shape, std::span<const std::uint8_t> frame) noexcept {
  if (!shape.check) return true;
  const FrameCheck& c = *shape.check;
  const std::uint16_t want = compute_check(*c.algorithm, frame.subspan(c.from, c.to - c.from));
  const FieldSpec f = field::typed(
      c.algorithm->size() == 2 ? field::FieldType::kU16 : field::FieldType::kU8, c.at, c.endian);
  return static_cast<std::uint16_t>(field::read_count(frame.data(), f)) == want;
}

void seal(const FrameShape& shape, std::span<std::uint8_t> frame) noexcept {
  std::copy(shape.sync.begin(), shape.sync.end(), frame.begin());
  if (!shape.check) return;
  const FrameCheck& c = *shape.check;
  const std::uint16_t v = compute_check(*c.algorithm, frame.subspan(c.from, c.to - c.from));
  const FieldSpec f = field::typed(
      c.algorithm->size() == 2 ? field::FieldType::kU16 : field::FieldType::kU8, c.at, c.endian);
  field::write_raw(frame.data(), f, v);
}

void decode_input(std::span<const std::uint8_t> frame, const InputLayout& layout,
                  InputValues& out) noexcept {
  const std::uint8_t* d = frame.data();
  for (std::size_t i = 0; i < layout.positions.size(); ++i) {
    out.position[i] = field::read_si(d, layout.positions[i]);
  }
  if (layout.sequence)
    out.sequence = static_cast<std::uint32_t>(field::read_count(d, *layout.sequence));
  if (layout.status) out.status = static_cast<std::uint32_t>(field::read_count(d, *layout.status));
}

void encode_input(const InputValues& in, const InputLayout& layout,
                  std::span<std::uint8_t> frame) noexcept {
  std::fill(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(layout.shape.length), 0);
  std::uint8_t* d = frame.data();
  for (std::size_t i = 0; i < layout.positions.size(); ++i) {
    field::write_si(d, layout.positions[i], in.position[i]);
  }
  if (layout.sequence) field::write_wrapped(d, *layout.sequence, in.sequence);
  if (layout.status) field::write_raw(d, *layout.status, in.status);
  seal(layout.shape, frame);
}

void encode_output(std::span<const double> forces, bool enable, const OutputLayout& layout,
                   std::span<std::uint8_t> frame) noexcept {
  std::fill(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(layout.shape.length), 0);
  std::uint8_t* d = frame.data();
  for (std::size_t i = 0; i < layout.forces.size() && i < forces.size(); ++i) {
    field::write_si(d, layout.forces[i], forces[i]);
  }
  if (layout.enable) {
    field::write_raw(d, layout.enable->field, enable ? layout.enable->on : layout.enable->off);
  }
  seal(layout.shape, frame);
}

void decode_output(std::span<const std::uint8_t> frame, const OutputLayout& layout,
                   OutputValues& out) noexcept {
  const std::uint8_t* d = frame.data();
  for (std::size_t i = 0; i < layout.forces.size(); ++i) {
    out.force[i] = field::read_si(d, layout.forces[i]);
  }
  out.enable = !layout.enable || field::read_raw(d, layout.enable->field) == layout.enable->on;
}

void FrameScanner::compact() noexcept {
  if (start_ == 0) return;
  std::memmove(buf_.data(), buf_.data() + start_, size_ - start_);
  size_ -= start_;
  start_ = 0;
}

void FrameScanner::push(std::span<const std::uint8_t> bytes) noexcept {
  if (size_ + bytes.size() > buf_.size()) compact();
  if (bytes.size() >= buf_.size()) {  // more than the buffer: the newest bytes are kept
    counts_.overflowed += size_ + bytes.size() - buf_.size();
    bytes = bytes.last(buf_.size());
    size_ = 0;
  } else if (size_ + bytes.size() > buf_.size()) {
    const std::size_t drop = size_ + bytes.size() - buf_.size();
    counts_.overflowed += drop;
    start_ = drop;
    compact();
  }
  std::memcpy(buf_.data() + size_, bytes.data(), bytes.size());
  size_ += bytes.size();
}

std::span<const std::uint8_t> FrameScanner::next() noexcept {
  const FrameShape& s = *shape_;
  while (size_ > start_) {
    const std::size_t avail = size_ - start_;
    const std::size_t n = std::min(avail, s.sync.size());
    if (n > 0 && std::memcmp(buf_.data() + start_, s.sync.data(), n) != 0) {
      ++counts_.skipped;
      ++start_;
      continue;
    }
    if (avail < s.length) break;
    const std::span<const std::uint8_t> frame(buf_.data() + start_, s.length);
    if (!check_ok(s, frame)) {
      ++counts_.bad_check;
      ++start_;
      continue;
    }
    start_ += s.length;
    ++counts_.frames;
    return frame;
  }
  if (start_ == size_) start_ = size_ = 0;
  return {};
}

}  // namespace hapticd::drivers::serial
