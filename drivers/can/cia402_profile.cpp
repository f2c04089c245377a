// The CiA 402 drive's lifecycle after configure (cia402_configure.cpp) and its tick.
#include "drivers/can/cia402_profile.h"

#include <algorithm>
#include <cmath>

#include "base/clock.h"

namespace hapticd::drivers::can {
namespace {

using cia402::PowerState;

// The stop's SDO exchanges: an EMCY among their answers is counted, not thrown (note_async).
class InStop {
 public:
  explicit InStop(bool& flag) noexcept : flag_(flag) { flag_ = true; }
  ~InStop() { flag_ = false; }
  InStop(const InStop&) = delete;
  InStop& operator=(const InStop&) = delete;

 private:
  bool& flag_;
};

}  // namespace

void Cia402Node::walk_to_enabled() {
  std::uint16_t sw = 0;
  PowerState state = read_state(sw);
  for (int step = 0; state != PowerState::kOperationEnabled; ++step) {
    const auto cw = cia402::step_towards_enabled(state);
    if (!cw || step > 6) {
      throw DeviceError("can: node " + std::to_string(node_.node_id) + " cannot be enabled from " +
                        cia402::describe_statusword(sw) +
                        (state == PowerState::kFault ? ", " + drive_error_text() : ""));
    }
    state = take_step(state, *cw, sw);
  }
}

// One controlword, confirmed from the statusword within state_timeout_ms. A drive in switch
// on disabled without voltage (bit 4 at 0) is given dc_link_timeout_ms for its DC link to
// charge, the controlword written again every kDcLinkResendMs (a drive may act on it only
// once charged), and refused naming the DC link if it never does.
PowerState Cia402Node::take_step(PowerState from, std::uint16_t cw, std::uint16_t& sw) {
  constexpr int kDcLinkResendMs = 100;
  sdo_write(cia402::kControlword, cw, 2, "controlword");
  const std::int64_t start = base::monotonic_ms();
  const std::int64_t step_deadline = start + settings_.state_timeout_ms;
  const std::int64_t dc_link_deadline =
      std::max(step_deadline, start + settings_.cia402.dc_link_timeout_ms);
  std::int64_t resend_at = start + kDcLinkResendMs;
  PowerState state = from;
  bool charging = false;
  while ((state = read_state(sw)) == from) {
    charging = from == PowerState::kSwitchOnDisabled && (sw & cia402::kSwVoltageEnabled) == 0;
    const std::int64_t now = base::monotonic_ms();
    if (now >= (charging ? dc_link_deadline : step_deadline)) break;
    if (charging && now >= resend_at) {
      sdo_write(cia402::kControlword, cw, 2, "controlword");
      resend_at = now + kDcLinkResendMs;
    }
    link_.wait_readable(2);  // the drive's own cycle moves it on; ask again shortly
  }
  if (state != from) return state;
  const std::string node = "can: node " + std::to_string(node_.node_id);
  if (charging) {
    throw DeviceError(
        node + ": the drive reports no DC-link voltage (statusword " +
        cia402::describe_statusword(sw) + ": bit 4, voltage enabled, is 0) after " +
        std::to_string(std::max(settings_.state_timeout_ms, settings_.cia402.dc_link_timeout_ms)) +
        " ms: it stays in switch on disabled until its DC link has charged, so controlword " +
        hex(cw, 4) +
        " cannot switch it on. Check its mains (power stage) supply: the contactor, fuses, "
        "wiring, the safe torque off input; a DC link that charges more slowly needs a longer "
        "device.can.cia402.dc_link_timeout_ms (" +
        std::to_string(settings_.cia402.dc_link_timeout_ms) + ")");
  }
  throw DeviceError(node + ": controlword " + hex(cw, 4) + " did not move the drive out of " +
                    std::string(cia402::to_string(from)) + " within " +
                    std::to_string(settings_.state_timeout_ms) + " ms (statusword " +
                    cia402::describe_statusword(sw) + ")");
}

void Cia402Node::enable() {
  const std::uint8_t node = node_.node_id;
  const Cia402Settings& c = settings_.cia402;
  sdo_write(cia402::kTargetTorque, 0, 2, "target torque");
  if (has_cycle_period_) {  // the last stop switched the SYNC watch off
    sdo_write(cia402::kCommunicationCyclePeriod,
              static_cast<std::uint32_t>(std::lround(period_s_ * 1e6)), 4,
              "communication cycle period");
  }
  if (c.drive_watchdog_ms > 0) {
    sdo_write(cia402::kConsumerHeartbeatTime,
              (static_cast<std::uint32_t>(c.master_node_id) << 16) |
                  static_cast<std::uint32_t>(c.drive_watchdog_ms),
              4, "consumer heartbeat time");
  }
  link_.send(canopen::nmt_command(canopen::NmtCommand::kStart, node), "NMT start");
  walk_to_enabled();
}

// Zero torque and the power stage off together, applied at the next SYNC slot.
CanFrame Cia402Node::shutdown_frame() const noexcept {
  return canopen::rpdo1_frame(node_.node_id, cia402::kCwShutdown, 0);
}

void Cia402Node::enter_pre_operational() noexcept {
  link_.send_quietly(
      canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node_.node_id));
}

// The shutdown RPDO is a frame nobody answers: a drive that missed it (a frame lost, or taken
// after the SYNC meant to apply it: over vcan, frames sent from two CPUs can arrive in either
// order) keeps its last torque. The statusword (SDO) says; a drive still in Operation enabled
// is given zero torque and the shutdown by SDO, each confirmed, and then asked again. False
// when it stays enabled past state_timeout_ms or cannot be asked.
bool Cia402Node::confirm_off() noexcept {
  const InStop in_stop(stopping_);
  try {
    std::uint16_t sw = 0;
    const std::int64_t deadline = base::monotonic_ms() + settings_.state_timeout_ms;
    while (read_state(sw) == PowerState::kOperationEnabled) {
      if (base::monotonic_ms() >= deadline) return false;
      sdo_write(cia402::kTargetTorque, 0, 2, "target torque");
      sdo_write(cia402::kControlword, cia402::kCwShutdown, 2, "controlword (shutdown)");
      link_.wait_readable(2);
    }
    return true;
  } catch (...) {
    return false;  // no answer: the bus or the drive is gone, and its watchdogs stay on
  }
}

// While SYNC and hapticd's heartbeat still come: the drive stops watching them, so their end
// is no lost master (CANopenNode: EMCY 0x8100 at 1.5 cycles without SYNC, 0x8130 when the
// heartbeat consumer times out, both in pre-operational too).
void Cia402Node::stop_keeping_alive() noexcept {
  const InStop in_stop(stopping_);
  try {
    if (has_cycle_period_) {
      sdo_write(cia402::kCommunicationCyclePeriod, 0, 4,
                "communication cycle period (0: the SYNC watch off)");
    }
    if (settings_.cia402.drive_watchdog_ms > 0) {
      sdo_write(cia402::kConsumerHeartbeatTime, 0, 4, "consumer heartbeat time");
    }
  } catch (...) {
    // Best effort: the power stage is already off, and a lost bus is reported elsewhere.
  }
}

void Cia402Node::clear_fault() {
  const std::uint8_t node = node_.node_id;
  link_.send(canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node), "NMT");
  sdo_write(cia402::kControlword, cia402::kCwDisableVoltage, 2, "controlword");
  sdo_write(cia402::kControlword, cia402::kCwFaultReset, 2, "controlword (fault reset)");
  std::uint16_t sw = 0;
  PowerState state = read_state(sw);
  const std::int64_t deadline = base::monotonic_ms() + settings_.state_timeout_ms;
  while (state == PowerState::kFault && base::monotonic_ms() < deadline) {
    link_.wait_readable(2);
    state = read_state(sw);
  }
  sdo_write(cia402::kControlword, cia402::kCwDisableVoltage, 2, "controlword");
  if (state == PowerState::kFault || state == PowerState::kFaultReactionActive) {
    throw DeviceError("can: node " + std::to_string(node) + ": the fault reset did not clear " +
                      "the fault (statusword " + cia402::describe_statusword(sw) + ", " +
                      drive_error_text() + ")");
  }
}

// --- the tick ---

FrameMeaning Cia402Node::on_tpdo1(const CanSocket::Received& rx, bool active) noexcept {
  const auto pdo = canopen::decode_tpdo1(rx.frame);
  if (!pdo) {
    link_.count(CanCounter::kWrongLength);
    return {};
  }
  FrameMeaning m;
  m.sample = true;
  statusword_ = pdo->statusword;
  position_.next(static_cast<std::uint32_t>(pdo->position));
  sample_time_ns_ = rx.time_ns;
  if (active && (statusword_ & cia402::kSwInternalLimitActive) != 0) {
    link_.count(CanCounter::kInternalLimit);
  }
  const PowerState s = cia402::decode_statusword(statusword_);
  if (s == PowerState::kFault || s == PowerState::kFaultReactionActive) {
    m.fault = {CanFaultKind::kStatuswordFault, statusword_};
  } else if (active && s != PowerState::kOperationEnabled) {
    m.fault = {CanFaultKind::kLeftOperation, statusword_};
  }
  return m;
}

FrameMeaning Cia402Node::on_emcy(const CanFrame& f) noexcept {
  const auto e = canopen::decode_emcy(f);
  FrameMeaning m;
  if (!e) {
    m.fault = {CanFaultKind::kEmcyTruncated, f.len};
  } else if (e->code == 0) {
    link_.count(CanCounter::kEmcyResets);
  } else {
    m.fault = {CanFaultKind::kEmcy,
               (static_cast<std::uint32_t>(e->error_register) << 16) | e->code};
  }
  return m;
}

FrameMeaning Cia402Node::on_heartbeat(const CanFrame& f, bool active) noexcept {
  const auto s = canopen::decode_heartbeat(f);
  if (!s) {
    link_.count(CanCounter::kWrongLength);
    return {};
  }
  FrameMeaning m;
  m.heartbeat = true;
  if (active && *s != canopen::NmtState::kOperational) {
    m.fault = {CanFaultKind::kNmtStateChanged, static_cast<std::uint32_t>(*s)};
  }
  return m;
}

bool Cia402Node::owns(const CanFrame& f) const noexcept {
  const std::uint8_t node = node_.node_id;
  return !f.extended && !f.rtr &&
         (f.id == canopen::kTpdo1Base + node ||
          (f.id == canopen::kTpdo2Base + node && settings_.cia402.map_velocity) ||
          f.id == canopen::kEmcyBase + node || f.id == canopen::kHeartbeatBase + node);
}

// A frame owns() says is this node's.
FrameMeaning Cia402Node::on_frame(const CanSocket::Received& rx, bool active) noexcept {
  const CanFrame& f = rx.frame;
  const std::uint8_t node = node_.node_id;
  if (f.id == canopen::kTpdo1Base + node) {
    return on_tpdo1(rx, active);
  } else if (f.id == canopen::kTpdo2Base + node && settings_.cia402.map_velocity) {
    if (const auto v = canopen::decode_tpdo2(f)) {
      velocity_ = *v;
    } else {
      link_.count(CanCounter::kWrongLength);
    }
  } else if (f.id == canopen::kEmcyBase + node) {
    return on_emcy(f);
  } else if (f.id == canopen::kHeartbeatBase + node) {
    return on_heartbeat(f, active);
  }
  return {};
}

void Cia402Node::sample(PositionSample& out) const noexcept {
  out.position = static_cast<double>(position_.value()) * node_.position_per_unit;
  out.time_ns = sample_time_ns_;
  out.status = statusword_;
  out.flags = kSampleHasTime;
  if (settings_.cia402.map_velocity) {
    out.velocity = velocity_ * node_.position_per_unit;
    out.flags |= kSampleHasVelocity;
  }
}

CanFrame Cia402Node::rpdo(double force) const noexcept {
  const double permille =
      std::clamp(force * permille_per_force_, -1.0 * max_permille_, 1.0 * max_permille_);
  const auto torque = static_cast<std::int16_t>(std::lround(permille));
  return canopen::rpdo1_frame(node_.node_id, cia402::kCwEnableOperation, torque);
}

std::string Cia402Node::describe(const CanFault& f) const {
  const std::string node = "can: cia402 node " + std::to_string(node_.node_id);
  switch (f.kind) {
    case CanFaultKind::kEmcy:
      return node + " sent EMCY " + canopen::describe_emcy_code(f.code & 0xFFFF) +
             " (error register " + hex((f.code >> 16) & 0xFF, 2) + ")";
    case CanFaultKind::kEmcyTruncated:
      return node + " sent an EMCY frame truncated to " + std::to_string(f.code) +
             " bytes (an EMCY carries 8): treated as an emergency";
    case CanFaultKind::kStatuswordFault:
      return node + " reports a fault in its statusword (" +
             cia402::describe_statusword(static_cast<std::uint16_t>(f.code)) + ")";
    case CanFaultKind::kLeftOperation:
      return node + " left Operation enabled by itself (statusword " +
             cia402::describe_statusword(static_cast<std::uint16_t>(f.code)) + ")";
    case CanFaultKind::kNmtStateChanged:
      return node + " left NMT operational: its heartbeat says " +
             std::string(canopen::to_string(static_cast<canopen::NmtState>(f.code)));
    case CanFaultKind::kHeartbeatLost:
      return node + ": no heartbeat (" + hex(canopen::kHeartbeatBase + node_.node_id, 3) +
             ") for " + std::to_string(f.code) + " ticks (heartbeat_timeout_ms " +
             std::to_string(settings_.heartbeat_timeout_ms) + ")";
    default:
      return {};  // the bus's: the device names it
  }
}

}  // namespace hapticd::drivers::can
