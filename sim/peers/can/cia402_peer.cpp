#include "sim/peers/can/cia402_peer.h"

#include <cmath>
#include <limits>

#include "base/clock.h"

namespace hapticd::sim {
namespace {

using drivers::can::CanFrame;
using drivers::can::canopen::NmtCommand;
using drivers::can::canopen::NmtState;
using drivers::can::canopen::SdoAddress;
using drivers::can::canopen::SdoRequest;
using drivers::can::cia402::PowerState;
namespace canopen = drivers::can::canopen;
namespace cia402 = drivers::can::cia402;

// CiA 301 abort codes the server answers with.
constexpr std::uint32_t kNoObject = 0x06020000;
constexpr std::uint32_t kNoSubindex = 0x06090011;
constexpr std::uint32_t kReadOnly = 0x06010002;
constexpr std::uint32_t kWrongState = 0x08000022;
constexpr std::uint32_t kCannotMap = 0x06040041;
constexpr std::uint32_t kTooLong = 0x06040042;

bool is_pdo_comm(std::uint16_t i) {
  return (i >= 0x1400 && i <= 0x1403) || (i >= 0x1800 && i <= 0x1803);
}
bool is_pdo_map(std::uint16_t i) {
  return (i >= 0x1600 && i <= 0x1603) || (i >= 0x1A00 && i <= 0x1A03);
}
bool mappable(std::uint32_t entry) {
  const std::uint32_t object = entry >> 8;  // index and subindex without the length
  return object == 0x604000 || object == 0x607100 || object == 0x604100 || object == 0x606400 ||
         object == 0x606C00;
}

}  // namespace

Cia402Peer::Cia402Peer(const config::Config& cfg, drivers::can::CanSocket socket, bool realtime,
                       const SharedJoint& joint)
    : CanPeerBase(cfg, std::move(socket), realtime,
                  {CanPeerFault::kStopSdo, CanPeerFault::kAbortSdo, CanPeerFault::kTruncatedEmcy},
                  joint),
      node_(settings_.nodes.front().node_id) {
  // Factory defaults: the predefined connection set, with a mapping that is not hapticd's
  // (RPDO1 controlword only, TPDO1 statusword only, event-driven): `pdo_mapping: verify`
  // against a factory-fresh drive must fail, as it would on a real one.
  for (std::uint16_t i = 0; i < 4; ++i) {
    const std::uint32_t valid = i < 2 ? 0 : cia402::kCobIdInvalid;
    od_[{static_cast<std::uint16_t>(0x1400 + i), 1}] = valid | (0x200u + 0x100u * i + node_);
    od_[{static_cast<std::uint16_t>(0x1400 + i), 2}] = 255;
    od_[{static_cast<std::uint16_t>(0x1800 + i), 1}] = valid | (0x180u + 0x100u * i + node_);
    od_[{static_cast<std::uint16_t>(0x1800 + i), 2}] = 255;
    for (std::uint8_t sub = 0; sub <= 8; ++sub) {
      od_[{static_cast<std::uint16_t>(0x1600 + i), sub}] = 0;
      od_[{static_cast<std::uint16_t>(0x1A00 + i), sub}] = 0;
    }
  }
  od_[{0x1600, 0}] = 1;
  od_[{0x1600, 1}] = 0x60400010;
  od_[{0x1A00, 0}] = 1;
  od_[{0x1A00, 1}] = 0x60410010;
  od_[{0x1001, 0}] = 0;
  od_[{0x1006, 0}] = 0;
  od_[{0x1016, 1}] = 0;
  od_[{0x1017, 0}] = 0;
  od_[{0x6007, 0}] = 1;
  od_[{0x6060, 0}] = 0;
  od_[{0x6072, 0}] = 3000;  // max torque: 300 % of the rated torque, in per mille
  od_[{0x60C2, 1}] = 1;     // interpolation time period: 1 x 10^-3 s
  od_[{0x60C2, 2}] = static_cast<std::uint8_t>(-3);
  publish();
}

std::uint32_t Cia402Peer::object(std::uint16_t index, std::uint8_t sub) const {
  const auto it = od_.find({index, sub});
  return it == od_.end() ? 0 : it->second;
}

std::int32_t Cia402Peer::position_units() noexcept {
  const auto units =
      std::llround(axis_.encoder_position() / settings_.nodes.front().position_per_unit) +
      position_offset_.load();
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(units));  // modulo 2^32
}

void Cia402Peer::set_power(PowerState s) {
  const bool was = cia402::torque_enabled(power_.load());
  power_.store(s);
  const bool on = cia402::torque_enabled(s) && s == PowerState::kOperationEnabled;
  if (on != was) axis_.set_output(on);
  // Torque follows 0x6071 only in operation enabled and mode 10 (cyclic synchronous torque).
  if (on && static_cast<std::int8_t>(object(0x6060, 0)) == cia402::kModeCyclicSynchronousTorque) {
    axis_.hold_force(target_torque_ * static_cast<double>(kRatedTorqueMilliNm) /
                     (1e6 * settings_.nodes.front().torque_per_force));
  } else if (on) {
    axis_.hold_force(0.0);
  }
}

void Cia402Peer::charge_dc_link_after(int ms) noexcept {
  dc_link_charged_ns_.store(ms < 0 ? std::numeric_limits<std::int64_t>::max()
                                   : base::monotonic_ns() + ms * 1'000'000LL);
}

void Cia402Peer::set_controlword(std::uint16_t cw) {
  const PowerState now = power_.load();
  PowerState next = cia402::apply_controlword(now, cw, controlword_);
  controlword_ = cw;
  // Without DC-link voltage the drive stays in switch on disabled (transition 2 refused); the
  // command counts when it comes again once charged.
  if (now == PowerState::kSwitchOnDisabled && base::monotonic_ns() < dc_link_charged_ns_.load()) {
    next = now;
  }
  set_power(next);
}

void Cia402Peer::enter_fault(std::uint16_t emcy_code, std::uint8_t error_register) {
  error_code_ = emcy_code;
  od_[{0x1001, 0}] = error_register;
  set_power(PowerState::kFault);
  send(canopen::emcy_frame(node_, emcy_code, error_register));
}

void Cia402Peer::lose_master(std::uint16_t emcy_code) {
  send(canopen::emcy_frame(node_, emcy_code, 0x11));  // generic + communication
  on_bus_lost();
}

void Cia402Peer::on_bus_lost() {
  switch (static_cast<cia402::CommLossReaction>(object(0x6007, 0))) {
    case cia402::CommLossReaction::kNone:
      return;  // the drive keeps its last torque: the case 0x6007 exists to prevent
    case cia402::CommLossReaction::kFault:
      error_code_ = 0x8100;
      set_power(PowerState::kFault);
      return;
    default:  // disable voltage, or quick stop (which ends there in torque mode)
      set_power(PowerState::kSwitchOnDisabled);
  }
}

void Cia402Peer::apply_device_fault() { enter_fault(kFaultEmcyCode, 0x03); }

std::uint32_t Cia402Peer::write_object(SdoAddress at, std::uint32_t value) {
  const std::uint16_t i = at.index;
  if (i == 0x6040 && at.subindex == 0) {
    set_controlword(static_cast<std::uint16_t>(value));
    return 0;
  }
  if (i == 0x6071 && at.subindex == 0) {
    target_torque_ = static_cast<std::int16_t>(value);
    set_power(power_.load());
    return 0;
  }
  if (i == 0x1000 || i == 0x1001 || i == 0x1018 || i == 0x603F || i == 0x6041 || i == 0x6061 ||
      i == 0x6064 || i == 0x606C || i == 0x6076) {
    return kReadOnly;
  }
  const auto it = od_.find({i, at.subindex});
  if (it == od_.end())
    return od_.lower_bound({i, 0}) != od_.end() && od_.lower_bound({i, 0})->first.first == i
               ? kNoSubindex
               : kNoObject;
  if (is_pdo_map(i)) {
    // CiA 301: a mapping changes only while its PDO is invalid, in pre-operational.
    const std::uint16_t comm = static_cast<std::uint16_t>(i - 0x200);
    if (nmt_ == NmtState::kOperational || (object(comm, 1) & cia402::kCobIdInvalid) == 0) {
      return kWrongState;
    }
    if (at.subindex > 0 && !mappable(value)) return kCannotMap;
    if (at.subindex == 0) {
      int bits = 0;
      for (std::uint8_t s = 1; s <= value && s <= 8; ++s) bits += object(i, s) & 0xFF;
      if (value > 8 || bits > 64) return kTooLong;
    }
  }
  if (is_pdo_comm(i) && at.subindex == 1 && nmt_ == NmtState::kOperational) return kWrongState;
  it->second = value;
  if (i == 0x6060) set_power(power_.load());
  return 0;
}

bool Cia402Peer::read_object(SdoAddress at, std::uint32_t& value, std::uint8_t& size) {
  const auto power = power_.load();
  size = 4;
  switch (at.index) {
    case 0x1000:
      value = 0x00020192;
      return at.subindex == 0;  // servo drive, profile 402
    case 0x1018:
      value = 0;
      return at.subindex == 1;  // vendor id: none assigned
    case 0x603F:
      value = error_code_;
      size = 2;
      return true;
    case 0x6040:
      value = controlword_;
      size = 2;
      return true;
    case 0x6041:
      value = cia402::encode_statusword(power);
      size = 2;
      return true;
    case 0x6061:
      value = object(0x6060, 0);
      size = 1;
      return true;
    case 0x6064:
      value = static_cast<std::uint32_t>(position_units());
      return true;
    case 0x6071:
      value = static_cast<std::uint16_t>(target_torque_);
      size = 2;
      return true;
    case 0x6076:
      value = kRatedTorqueMilliNm;
      return true;
    default:
      break;
  }
  const auto it = od_.find({at.index, at.subindex});
  if (it == od_.end()) return false;
  value = it->second;
  const bool byte = at.index == 0x1001 || at.index == 0x6060 || at.index == 0x60C2 ||
                    (is_pdo_map(at.index) && at.subindex == 0) ||
                    (is_pdo_comm(at.index) && at.subindex == 2);
  size = byte ? 1 : (at.index == 0x1017 || at.index == 0x6007 || at.index == 0x6072) ? 2 : 4;
  return true;
}

void Cia402Peer::on_sdo(const CanFrame& f) {
  if (can_faults_.active(CanPeerFault::kStopSdo) || nmt_ == NmtState::kStopped) return;
  const SdoRequest r = canopen::decode_sdo_request(f);
  if (can_faults_.take(CanPeerFault::kAbortSdo)) {
    send(canopen::sdo_abort_frame(node_, canopen::kSdoTxBase, r.at, kWrongState));
    return;
  }
  if (r.kind == SdoRequest::Kind::kDownload) {
    const std::uint32_t abort = write_object(r.at, r.value);
    send(abort == 0 ? canopen::sdo_download_confirm(node_, r.at)
                    : canopen::sdo_abort_frame(node_, canopen::kSdoTxBase, r.at, abort));
  } else if (r.kind == SdoRequest::Kind::kUpload) {
    std::uint32_t value = 0;
    std::uint8_t size = 4;
    if (read_object(r.at, value, size)) {
      send(canopen::sdo_upload_reply(node_, r.at, value, size));
    } else {
      send(canopen::sdo_abort_frame(node_, canopen::kSdoTxBase, r.at, kNoObject));
    }
  } else if (r.kind == SdoRequest::Kind::kUnsupported) {
    send(canopen::sdo_abort_frame(node_, canopen::kSdoTxBase, r.at, 0x05040001));
  }
}

void Cia402Peer::on_nmt(NmtCommand c) {
  switch (c) {
    case NmtCommand::kStart:
      nmt_ = NmtState::kOperational;
      synced_ = false;
      break;
    case NmtCommand::kStop:
      nmt_ = NmtState::kStopped;
      break;
    default:  // pre-operational, and the resets (which end there after the boot-up message)
      if (c != NmtCommand::kEnterPreOperational)
        send(canopen::heartbeat_frame(node_, NmtState::kBootUp));
      nmt_ = NmtState::kPreOperational;
      break;
  }
  pending_rpdo_ = false;
}

void Cia402Peer::on_rpdo(const CanFrame& f) {
  // Unpack through 0x1600's mapping; a frame that does not match its length is refused
  // (EMCY 0x8210), as CiA 301 has it.
  const std::uint32_t count = object(0x1600, 0);
  int bytes = 0;
  for (std::uint8_t s = 1; s <= count && s <= 8; ++s) bytes += (object(0x1600, s) & 0xFF) / 8;
  if (f.len != bytes || f.rtr) {
    send(canopen::emcy_frame(node_, 0x8210, 0x11));
    return;
  }
  int at = 0;
  for (std::uint8_t s = 1; s <= count && s <= 8; ++s) {
    const std::uint32_t e = object(0x1600, s);
    const std::uint16_t v = drivers::can::get_u16(f, at);
    if ((e >> 16) == 0x6040) pending_cw_ = v;
    if ((e >> 16) == 0x6071) pending_torque_ = static_cast<std::int16_t>(v);
    at += static_cast<int>((e & 0xFF) / 8);
  }
  if (object(0x1400, 2) <= 240) {
    pending_rpdo_ = true;  // synchronous: takes effect at the next SYNC
  } else {
    target_torque_ = pending_torque_;
    set_controlword(pending_cw_);
  }
}

}  // namespace hapticd::sim
