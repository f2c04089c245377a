// The reference CiA 402 drive's object dictionary and SDO server, by CANopenNode's rules
// (cia402_drive.h says which file each rule comes from).
#include "reference/can/cia402_drive.h"

namespace hapticd::reference {
namespace {

// CO_ODinterface.c, OD_getSDOabCode; CiA 301 7.2.4.3.17.
constexpr std::uint32_t kUnsupportedAccess = 0x06010000;
constexpr std::uint32_t kReadOnly = 0x06010002;
constexpr std::uint32_t kNoObject = 0x06020000;
constexpr std::uint32_t kNoMap = 0x06040041;
constexpr std::uint32_t kMapLength = 0x06040042;
constexpr std::uint32_t kDataLong = 0x06070012;
constexpr std::uint32_t kDataShort = 0x06070013;
constexpr std::uint32_t kNoSubindex = 0x06090011;
constexpr std::uint32_t kInvalidValue = 0x06090030;
constexpr std::uint32_t kCommandSpecifier = 0x05040001;

bool is_pdo_comm(std::uint16_t i) {
  return (i >= 0x1400 && i <= 0x1403) || (i >= 0x1800 && i <= 0x1803);
}
bool is_pdo_map(std::uint16_t i) {
  return (i >= 0x1600 && i <= 0x1603) || (i >= 0x1A00 && i <= 0x1A03);
}

// CO_driver.h, CO_IS_RESTRICTED_CAN_ID.
bool restricted(std::uint32_t id) {
  return id <= 0x7F || (id >= 0x101 && id <= 0x180) || (id >= 0x581 && id <= 0x5FF) ||
         (id >= 0x601 && id <= 0x67F) || (id >= 0x6E0 && id <= 0x6FF) || id >= 0x701;
}

Frame abort_frame(std::uint8_t node, std::uint16_t index, std::uint8_t sub, std::uint32_t code) {
  Frame f = make_frame(0x580u + node, 8);
  f.data[0] = 0x80;
  f.put_u16(1, index);
  f.data[3] = sub;
  f.put_u32(4, code);
  return f;
}

}  // namespace

void Cia402Drive::add(std::uint16_t index, std::uint8_t sub, std::uint32_t value, std::uint8_t size,
                      bool writable, bool rpdo, bool tpdo) {
  od_[{index, sub}] = {value, size, writable, rpdo, tpdo};
}

void Cia402Drive::build_dictionary() {
  const std::uint32_t n = b_.node;
  add(0x1000, 0, 0x00020192, 4, false);  // servo drive, profile 402
  add(0x1001, 0, 0, 1, false, false, true);
  if (b_.has_1006) add(0x1006, 0, 0, 4, true);
  add(0x1016, 0, 1, 1, false);
  add(0x1016, 1, 0, 4, true);
  add(0x1017, 0, 0, 2, true);
  add(0x1018, 0, 1, 1, false);
  add(0x1018, 1, 0x000004C5, 4, false);
  // Factory PDOs as many drives ship them: RPDO1 and TPDO1 valid with the control and status
  // words only, TPDOs with bit 30 (no RTR) set, the others invalid.
  for (std::uint16_t i = 0; i < 4; ++i) {
    const bool first = i == 0;
    add(0x1400 + i, 0, 2, 1, false);
    add(0x1400 + i, 1, (first ? 0u : 0x80000000u) | (0x200u + 0x100u * i + n), 4, true);
    add(0x1400 + i, 2, 255, 1, true);
    add(0x1800 + i, 0, 2, 1, false);
    add(0x1800 + i, 1, (first ? 0x40000000u : 0xC0000000u) | (0x180u + 0x100u * i + n), 4, true);
    add(0x1800 + i, 2, 255, 1, true);
    add(0x1600 + i, 0, first ? 1 : 0, 1, true);
    add(0x1A00 + i, 0, first ? 1 : 0, 1, true);
    for (std::uint8_t s = 1; s <= 8; ++s) {
      add(0x1600 + i, s, first && s == 1 ? 0x60400010u : 0u, 4, true);
      add(0x1A00 + i, s, first && s == 1 ? 0x60410010u : 0u, 4, true);
    }
    pdos_[0x1400 + i] = {first, static_cast<std::uint8_t>(first ? 1 : 0)};
    pdos_[0x1800 + i] = {first, static_cast<std::uint8_t>(first ? 1 : 0)};
  }
  add(0x603F, 0, 0, 2, false);
  add(0x6040, 0, 0, 2, true, true, false);
  add(0x6041, 0, 0, 2, false, false, true);
  if (b_.has_6007) add(0x6007, 0, 1, 2, true);
  add(0x6060, 0, 0, 1, true, true, false);
  add(0x6061, 0, 0, 1, false, false, true);
  add(0x6064, 0, 0, 4, false, false, true);
  add(0x606C, 0, 0, 4, false, false, true);
  add(0x6071, 0, 0, 2, true, true, false);
  if (b_.max_torque_permille != 0) add(0x6072, 0, b_.max_torque_permille, 2, true, true, false);
  add(0x6076, 0, b_.rated_torque_mnm, 4, false);
  if (b_.has_60c2) {
    add(0x60C2, 0, 2, 1, false);
    add(0x60C2, 1, 1, 1, true);
    add(0x60C2, 2, 0xFD, 1, true);  // 1 x 10^-3 s
  }
}

bool Cia402Drive::has_object(std::uint16_t index, std::uint8_t sub) const {
  return od_.count({index, sub}) != 0;
}

std::uint32_t Cia402Drive::object(std::uint16_t index, std::uint8_t sub) const {
  const auto it = od_.find({index, sub});
  return it == od_.end() ? 0 : it->second.value;
}

Cia402Drive::PdoState& Cia402Drive::pdo(std::uint16_t comm_index) { return pdos_[comm_index]; }

std::uint32_t Cia402Drive::write_pdo_comm(Key k, std::uint32_t value) {
  PdoState& p = pdo(k.index);
  const bool tpdo = k.index >= 0x1800;
  if (k.sub == 2) {
    return value > 240 && value < 254 ? kInvalidValue : 0;
  }
  if (k.sub != 1) return 0;
  const bool valid = (value & 0x80000000u) == 0;
  const std::uint32_t id = value & 0x7FF;
  const std::uint32_t configured = object(k.index, 1) & 0x7FF;
  if ((value & 0x3FFFF800u) != 0 || (valid && p.valid && id != configured) ||
      (valid && restricted(id)) || (valid && p.count == 0)) {
    return kInvalidValue;
  }
  // A drive that does not answer remote requests for its TPDOs insists on bit 30.
  if (tpdo && b_.tpdo_cob_id_bit30_required && (value & 0x40000000u) == 0) return kInvalidValue;
  p.valid = valid;
  return 0;
}

std::uint32_t Cia402Drive::write_pdo_mapping(Key k, std::uint32_t value) {
  const auto comm = static_cast<std::uint16_t>(k.index - 0x200);
  PdoState& p = pdo(comm);
  if (p.valid || (p.count != 0 && k.sub > 0)) return kUnsupportedAccess;
  if (k.sub == 0) {
    if (value > 8) return kMapLength;
    unsigned bits = 0;
    for (std::uint8_t s = 1; s <= value; ++s) bits += object(k.index, s) & 0xFF;
    if (bits > 64 || (bits == 0 && value > 0)) return bits > 64 ? kMapLength : kInvalidValue;
    p.count = static_cast<std::uint8_t>(value);
    return 0;
  }
  if (value == 0) return 0;
  const auto it =
      od_.find({static_cast<std::uint16_t>(value >> 16), static_cast<std::uint8_t>(value >> 8)});
  if (it == od_.end()) return kNoObject;
  const std::uint32_t bits = value & 0xFF;
  const bool rpdo = k.index < 0x1A00;
  if (!(rpdo ? it->second.rpdo : it->second.tpdo) || (bits & 7) != 0 ||
      bits / 8 > it->second.size || bits > 64) {
    return kNoMap;
  }
  return 0;
}

std::uint32_t Cia402Drive::write(Key k, std::uint32_t value, std::int64_t now_ns) {
  if (k.index == 0x6040) {
    apply_controlword(static_cast<std::uint16_t>(value));
  } else if (k.index == 0x6060) {
    mode_pending_ = static_cast<std::int8_t>(value);
    mode_shows_at_ns_ = now_ns + static_cast<std::int64_t>(b_.mode_display_lag_ms) * 1'000'000;
  } else if (k.index == 0x1016) {
    hb_state_ = 0;  // CO_HBconsumer: a new entry is unknown until its first heartbeat
  } else if (is_pdo_comm(k.index)) {
    if (const std::uint32_t a = write_pdo_comm(k, value)) return a;
  } else if (is_pdo_map(k.index)) {
    if (const std::uint32_t a = write_pdo_mapping(k, value)) return a;
  }
  od_[k].value = value;
  if (k.index == 0x6071 || k.index == 0x6072) apply_torque();
  return 0;
}

std::uint32_t Cia402Drive::read(Key k, std::uint32_t& value, std::uint8_t& size) const {
  const auto it = od_.find(k);
  if (it == od_.end()) {
    return od_.lower_bound({k.index, 0}) != od_.end() &&
                   od_.lower_bound({k.index, 0})->first.index == k.index
               ? kNoSubindex
               : kNoObject;
  }
  size = it->second.size;
  value = it->second.value;
  if (k.index == 0x6041) value = statusword();
  if (k.index == 0x6061) value = static_cast<std::uint8_t>(mode_shown_);
  if (k.index == 0x6064 || k.index == 0x606C) value = static_cast<std::uint32_t>(mapped(k.index));
  if (k.index == 0x603F) value = error_code_;
  return 0;
}

void Cia402Drive::on_sdo(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) {
  if (nmt_ == Nmt::kStopped || f.len != 8) return;
  const Key k{f.u16(1), f.data[3]};
  const std::uint8_t cs = f.data[0];
  std::uint32_t value = 0;
  std::uint8_t size = 4;
  if (cs == 0x40) {  // upload (read)
    if (const std::uint32_t a = read(k, value, size)) {
      out.push_back(abort_frame(b_.node, k.index, k.sub, a));
      return;
    }
    Frame r = make_frame(0x580u + b_.node, 8);
    r.data[0] = static_cast<std::uint8_t>(0x43 | ((4 - size) << 2));
    r.put_u16(1, k.index);
    r.data[3] = k.sub;
    r.put_u32(4, value);
    out.push_back(r);
    return;
  }
  if ((cs & 0xE0) != 0x20 || (cs & 0x02) == 0) {  // only expedited downloads
    out.push_back(abort_frame(b_.node, k.index, k.sub, kCommandSpecifier));
    return;
  }
  std::uint32_t a = read(k, value, size);
  if (a == 0 && !od_.at(k).writable) a = kReadOnly;
  if (a == 0 && (cs & 0x01) != 0) {  // size indicated: it must be the object's
    const int indicated = 4 - ((cs >> 2) & 3);
    if (indicated != size) a = indicated > size ? kDataLong : kDataShort;
  }
  if (a == 0) {
    value = f.u32(4);
    if (size < 4) value &= (1u << (8 * size)) - 1;
    a = write(k, value, now_ns);
  }
  if (a != 0) {
    out.push_back(abort_frame(b_.node, k.index, k.sub, a));
    return;
  }
  Frame r = make_frame(0x580u + b_.node, 8);
  r.data[0] = 0x60;
  r.put_u16(1, k.index);
  r.data[3] = k.sub;
  out.push_back(r);
}

}  // namespace hapticd::reference
