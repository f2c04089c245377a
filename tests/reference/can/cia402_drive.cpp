// The reference CiA 402 drive's NMT, SYNC, heartbeat, EMCY, PDOs and power state machine
// (cia402_drive.h says what each follows).
#include "reference/can/cia402_drive.h"

#include <algorithm>
#include <cmath>

namespace hapticd::reference {
namespace {

// CiA 402 statusword bits.
constexpr std::uint16_t kRemote = 1u << 9;
constexpr std::uint16_t kInternalLimit = 1u << 11;
constexpr std::uint16_t kVoltageEnabled = 1u << 4;
constexpr std::int8_t kCst = 10;

}  // namespace

Cia402Drive::Cia402Drive(const Cia402Behaviour& b, const PlantParameters& plant,
                         std::int64_t now_ns)
    : b_(b), plant_(plant, now_ns) {
  build_dictionary();
  heartbeat_sent_ns_ = now_ns;
  if (b.mains_on_at_start) mains_on_ns_.store(now_ns);
  update_dc_link(now_ns);
}

void Cia402Drive::update_dc_link(std::int64_t now_ns) {
  const std::int64_t mains = mains_on_ns_.load();
  dc_link_charged_ =
      mains >= 0 && now_ns - mains >= static_cast<std::int64_t>(b_.dc_link_charge_ms) * 1'000'000;
  // The shutdown command the drive holds is taken once its DC link has charged.
  if (dc_link_charged_ && shutdown_held_ && power_.load() == Power::kSwitchOnDisabled) {
    shutdown_held_ = false;
    if ((controlword_ & 0x87) == 0x06) set_power(Power::kReadyToSwitchOn);
  }
}

std::uint16_t Cia402Drive::statusword() const {
  std::uint16_t sw =
      kRemote | (limited_ ? kInternalLimit : 0) | (dc_link_charged_ ? kVoltageEnabled : 0);
  switch (power_.load()) {
    case Power::kSwitchOnDisabled:
      return sw | 0x0040;
    case Power::kReadyToSwitchOn:
      return sw | 0x0021;
    case Power::kSwitchedOn:
      return sw | 0x0033;
    case Power::kOperationEnabled:
      return sw | 0x0037;
    case Power::kQuickStopActive:
      return sw | 0x0017;
    case Power::kFault:
      return sw | 0x0008;
  }
  return sw;
}

std::int32_t Cia402Drive::mapped(std::uint16_t index) const {
  switch (index) {
    case 0x6041:
      return statusword();
    case 0x6061:
      return mode_shown_;
    case 0x6064: {  // INTEGER32: the count rolls over, modulo 2^32
      const std::int64_t count =
          std::llround(plant_.position() / b_.metres_per_increment) + b_.position_offset;
      return static_cast<std::int32_t>(static_cast<std::uint32_t>(count));
    }
    case 0x606C:
      return static_cast<std::int32_t>(std::lround(plant_.velocity() / b_.metres_per_increment));
    default:
      return static_cast<std::int32_t>(object(index, 0));
  }
}

void Cia402Drive::set_power(Power p) {
  power_.store(p);
  apply_torque();
}

// CST: the target torque acts in Operation enabled with mode 10 shown, clamped to 0x6072.
void Cia402Drive::apply_torque() {
  limited_ = false;
  if (power_.load() != Power::kOperationEnabled || mode_shown_ != kCst) {
    plant_.hold_motor_force(0.0);
    return;
  }
  double permille = static_cast<std::int16_t>(object(0x6071, 0));
  for (const double limit :
       {b_.max_torque_permille != 0 ? static_cast<double>(object(0x6072, 0) & 0xFFFF) : 0.0,
        static_cast<double>(b_.internal_limit_permille)}) {
    if (limit <= 0.0) continue;
    limited_ = limited_ || std::abs(permille) > limit;
    permille = std::clamp(permille, -limit, limit);
  }
  const double nm = permille * 1e-3 * b_.rated_torque_mnm * 1e-3;
  plant_.hold_motor_force(nm / b_.nm_per_newton);
}

// CiA 402 Table 31 (device control commands) on the state diagram's transitions.
void Cia402Drive::apply_controlword(std::uint16_t cw) {
  const std::uint16_t previous = controlword_;
  controlword_ = cw;
  const Power s = power_.load();
  if (s == Power::kFault) {
    if ((cw & 0x80) != 0 && (previous & 0x80) == 0) {  // fault reset: the rising edge of bit 7
      error_code_ = 0;
      set_power(Power::kSwitchOnDisabled);
    }
    return;
  }
  shutdown_held_ = false;  // a new command replaces one held for the DC link
  if ((cw & 0x02) == 0) {  // disable voltage
    set_power(Power::kSwitchOnDisabled);
  } else if ((cw & 0x04) == 0) {  // quick stop
    set_power(s == Power::kOperationEnabled ? Power::kQuickStopActive : Power::kSwitchOnDisabled);
  } else if (s == Power::kQuickStopActive) {
    // only disable voltage leaves it (above)
  } else if ((cw & 0x01) == 0) {  // shutdown
    if (s == Power::kSwitchOnDisabled && !dc_link_charged_) {
      shutdown_held_ = true;  // transition 2 waits for the DC link
      dc_link_refusals_.fetch_add(1);
      return;
    }
    set_power(Power::kReadyToSwitchOn);
  } else if ((cw & 0x08) == 0) {  // switch on / disable operation
    if (s != Power::kSwitchOnDisabled) set_power(Power::kSwitchedOn);
  } else if (s == Power::kSwitchedOn || s == Power::kReadyToSwitchOn ||
             s == Power::kOperationEnabled) {  // enable operation (3 + 4 from ready)
    set_power(Power::kOperationEnabled);
  }
}

void Cia402Drive::emcy(std::uint16_t code, std::vector<Frame>& out) {
  Frame f = make_frame(0x80u + b_.node, 8);
  f.put_u16(0, code);
  f.data[2] = code == 0 ? 0 : 0x11;  // generic + communication (error register 0x1001)
  out.push_back(f);
}

// 0x6007: what the drive does when it loses its master.
void Cia402Drive::lose_master(std::uint16_t code, std::vector<Frame>& out) {
  emcy(code, out);
  if (!b_.has_6007) {
    set_power(Power::kSwitchOnDisabled);  // the drive's own fixed reaction
    return;
  }
  const Power s = power_.load();
  switch (object(0x6007, 0)) {
    case 0:
      return;  // the last torque stays: what 0x6007 exists to prevent
    case 1:
      error_code_ = code;
      set_power(Power::kFault);
      return;
    default:
      if (s != Power::kFault) set_power(Power::kSwitchOnDisabled);
  }
}

void Cia402Drive::on_nmt(std::uint8_t command, std::vector<Frame>& out) {
  switch (command) {
    case 0x01:
      nmt_ = Nmt::kOperational;
      break;
    case 0x02:
      nmt_ = Nmt::kStopped;
      break;
    case 0x80:
      nmt_ = Nmt::kPreOperational;
      break;
    case 0x81:
    case 0x82: {
      Frame boot = make_frame(0x700u + b_.node, 1);
      out.push_back(boot);  // boot-up, then pre-operational
      nmt_ = Nmt::kPreOperational;
      break;
    }
    default:
      return;
  }
  if (nmt_ != Nmt::kOperational) rpdo_pending_ = false;
}

void Cia402Drive::on_rpdo(const Frame& f) {
  if (rpdos_to_lose_.load() > 0) {
    rpdos_to_lose_.fetch_sub(1);
    return;
  }
  // Unpacked through 0x1600 when the SYNC comes (synchronous), if its length matches.
  rpdo_frame_ = f;
  rpdo_pending_ = true;
}

void Cia402Drive::on_sync(std::int64_t now_ns, std::vector<Frame>& out) {
  plant_.advance_to(now_ns);
  if (sync_timeout_state_ == 2) emcy(0x0000, out);  // CO_errorReset: the SYNC is back
  sync_timeout_state_ = 1;
  last_sync_ns_ = now_ns;
  if (nmt_ != Nmt::kOperational) return;
  ++syncs_;
  if (rpdo_pending_) {
    rpdo_pending_ = false;
    const std::uint32_t count = object(0x1600, 0);
    int at = 0;
    int bytes = 0;
    for (std::uint8_t s = 1; s <= count; ++s)
      bytes += static_cast<int>((object(0x1600, s) & 0xFF) / 8);
    if (rpdo_frame_.len >= bytes) {
      for (std::uint8_t s = 1; s <= count; ++s) {
        const std::uint32_t e = object(0x1600, s);
        const int n = static_cast<int>((e & 0xFF) / 8);
        std::uint32_t v = 0;
        for (int i = 0; i < n; ++i)
          v |= static_cast<std::uint32_t>(rpdo_frame_.data[at + i]) << (8 * i);
        at += n;
        if ((e >> 16) == 0x6040) apply_controlword(static_cast<std::uint16_t>(v));
        if ((e >> 16) == 0x6071) od_[{0x6071, 0}].value = v;
      }
      apply_torque();
    } else {
      emcy(0x8210, out);  // PDO not processed due to length error
    }
  }
  for (std::uint16_t comm = 0x1800; comm <= 0x1803; ++comm) {
    const PdoState& p = pdo(comm);
    const std::uint32_t type = object(comm, 2);
    if (!p.valid || type == 0 || type > 240 || syncs_ % type != 0) continue;
    const auto map = static_cast<std::uint16_t>(comm + 0x200);
    Frame t = make_frame(object(comm, 1) & 0x7FF, 0);
    int at = 0;
    for (std::uint8_t s = 1; s <= p.count; ++s) {
      const std::uint32_t e = object(map, s);
      const int n = static_cast<int>((e & 0xFF) / 8);
      const auto v = static_cast<std::uint32_t>(mapped(static_cast<std::uint16_t>(e >> 16)));
      for (int i = 0; i < n && at + i < 8; ++i)
        t.data[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
      at += n;
    }
    t.len = static_cast<std::uint8_t>(std::min(at, 8));
    out.push_back(t);
  }
}

void Cia402Drive::on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) {
  plant_.advance_to(now_ns);
  update_dc_link(now_ns);
  const std::uint32_t master = (object(0x1016, 1) >> 16) & 0x7F;
  if (f.id == 0x000 && f.len == 2 && (f.data[1] == 0 || f.data[1] == b_.node)) {
    on_nmt(f.data[0], out);
  } else if (f.id == 0x080 && !f.rtr) {
    if (f.len == 0) on_sync(now_ns, out);
  } else if (f.id == 0x600u + b_.node) {
    on_sdo(f, now_ns, out);
  } else if (pdo(0x1400).valid && f.id == (object(0x1400, 1) & 0x7FF) &&
             nmt_ == Nmt::kOperational) {
    on_rpdo(f);
  } else if (master != 0 && f.id == 0x700u + master && f.len == 1) {
    if (nmt_ != Nmt::kStopped && (object(0x1016, 1) & 0xFFFF) != 0) {
      hb_state_ = 1;
      hb_last_ns_ = now_ns;
    }
  }
}

void Cia402Drive::on_clock(std::int64_t now_ns, std::vector<Frame>& out) {
  plant_.advance_to(now_ns);
  update_dc_link(now_ns);
  if (const std::uint16_t code = injected_fault_.exchange(0)) {
    error_code_ = code;
    set_power(Power::kFault);
    emcy(code, out);
  }
  if (mode_pending_ != mode_shown_ && now_ns >= mode_shows_at_ns_) {
    mode_shown_ = mode_pending_;
    apply_torque();
  }
  const std::uint32_t producer = object(0x1017, 0);
  if (producer != 0 &&
      now_ns - heartbeat_sent_ns_ >= static_cast<std::int64_t>(producer) * 1'000'000) {
    heartbeat_sent_ns_ = now_ns;
    Frame h = make_frame(0x700u + b_.node, 1);
    h.data[0] = static_cast<std::uint8_t>(nmt_);
    out.push_back(h);
  }
  if (nmt_ == Nmt::kStopped) {  // CO_SYNC_process / CO_HBconsumer_process: not watched
    last_sync_ns_ = now_ns;
    hb_state_ = 0;
    return;
  }
  const std::uint32_t period_us = b_.has_1006 ? object(0x1006, 0) : 0;
  if (period_us > 0 && sync_timeout_state_ == 1 &&
      now_ns - last_sync_ns_ > static_cast<std::int64_t>(period_us) * 1500) {
    sync_timeout_state_ = 2;
    if (b_.sync_loss_is_master_loss && power_.load() == Power::kOperationEnabled) {
      lose_master(0x8100, out);
    } else {
      emcy(0x8100, out);
    }
  }
  const std::uint32_t consumer_ms = object(0x1016, 1) & 0xFFFF;
  if (hb_state_ == 1 && consumer_ms != 0 &&
      now_ns - hb_last_ns_ > static_cast<std::int64_t>(consumer_ms) * 1'000'000) {
    hb_state_ = 2;
    lose_master(0x8130, out);
  }
}

}  // namespace hapticd::reference
