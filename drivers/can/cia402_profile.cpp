// The CiA 402 drive's lifecycle after configure (cia402_configure.cpp) and its tick.
#include "drivers/can/cia402_profile.h"

#include <algorithm>
#include <cmath>

#include "base/clock.h"

namespace hapticd::drivers::can {
namespace {

using cia402::PowerState;

}  // namespace

std::unique_ptr<CanProfile> make_cia402_profile(const CanSettings& s, double sample_period_s,
                                                int keeper_priority, CanLink& link) {
  return std::make_unique<Cia402Profile>(s, sample_period_s, keeper_priority, link);
}

void Cia402Profile::walk_to_enabled() {
  std::uint16_t sw = 0;
  PowerState state = read_state(sw);
  for (int step = 0; state != PowerState::kOperationEnabled; ++step) {
    const auto cw = cia402::step_towards_enabled(state);
    if (!cw || step > 6) {
      throw DeviceError("can: node " + std::to_string(settings_.node_id) +
                        " cannot be enabled from " + cia402::describe_statusword(sw) +
                        (state == PowerState::kFault ? ", " + drive_error_text() : ""));
    }
    state = take_step(state, *cw, sw);
  }
}

// One controlword, confirmed from the statusword within state_timeout_ms. A drive in switch
// on disabled without voltage (bit 4 at 0) is given dc_link_timeout_ms for its DC link to
// charge, the controlword written again every kDcLinkResendMs (a drive may act on it only
// once charged), and refused naming the DC link if it never does.
PowerState Cia402Profile::take_step(PowerState from, std::uint16_t cw, std::uint16_t& sw) {
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
  const std::string node = "can: node " + std::to_string(settings_.node_id);
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

void Cia402Profile::enable() {
  tick_ = 0;
  last_sync_ns_.store(0, std::memory_order_relaxed);
  stopped_ = false;  // from here on a failed enable is undone by the stop
  const std::uint8_t node = settings_.node_id;
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

void Cia402Profile::disable(const CanFault&) noexcept {
  if (stopped_) return;  // once per enable: a fault's disable and the close after it are one stop
  stopped_ = true;
  if (!link_.is_open()) return;
  const std::uint8_t node = settings_.node_id;
  // Zero torque and the power stage off together, applied at the next SYNC slot: one SYNC per
  // cycle, never two within microseconds (a drive's SYNC-locked clock would see a jump).
  link_.send_quietly(canopen::rpdo1_frame(node, cia402::kCwShutdown, 0));
  const auto period_ns = static_cast<std::int64_t>(std::llround(period_s_ * 1e9));
  const std::int64_t last = last_sync_ns_.load(std::memory_order_relaxed);
  std::vector<PeriodicSender::Entry> keep = {
      {canopen::sync_frame(), period_ns, last == 0 ? 0 : last + period_ns}};
  if (master_heartbeat_ticks_ != 0) {
    keep.push_back(
        {canopen::heartbeat_frame(settings_.cia402.master_node_id, canopen::NmtState::kOperational),
         static_cast<std::int64_t>(settings_.cia402.master_heartbeat_ms) * 1'000'000, 0});
  }
  try {
    keeper_.start(link_.fd(), std::move(keep), keeper_priority_);
    keeper_.wait_written(1);
  } catch (...) {
    link_.send_quietly(canopen::sync_frame());  // no thread to be had: the stop at least
  }
  const bool off = confirm_off();
  if (off) stop_keeping_alive();  // else its watchdogs end the torque once SYNC stops
  keeper_.stop();
  if (off) confirm_off();  // after the last SYNC: a late RPDO that enabled it again is undone
  link_.send_quietly(canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node));
}

// The shutdown RPDO is a frame nobody answers: a drive that missed it (a frame lost, or taken
// after the SYNC meant to apply it: over vcan, frames sent from two CPUs can arrive in either
// order) keeps its last torque. The statusword (SDO) says; a drive still in Operation enabled
// is given zero torque and the shutdown by SDO, each confirmed, and then asked again. False
// when it stays enabled past state_timeout_ms or cannot be asked.
bool Cia402Profile::confirm_off() noexcept {
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
void Cia402Profile::stop_keeping_alive() noexcept {
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

void Cia402Profile::clear_fault() {
  const std::uint8_t node = settings_.node_id;
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

FrameMeaning Cia402Profile::on_tpdo1(const CanSocket::Received& rx, bool active) noexcept {
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

FrameMeaning Cia402Profile::on_emcy(const CanFrame& f) noexcept {
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

FrameMeaning Cia402Profile::on_heartbeat(const CanFrame& f, bool active) noexcept {
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

FrameMeaning Cia402Profile::on_frame(const CanSocket::Received& rx, bool active) noexcept {
  const CanFrame& f = rx.frame;
  const std::uint8_t node = settings_.node_id;
  if (f.extended || f.rtr) {
    link_.count(CanCounter::kUnknownIds);
  } else if (f.id == canopen::kTpdo1Base + node) {
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
  } else {
    link_.count(CanCounter::kUnknownIds);  // late SDO answers too
  }
  return {};
}

void Cia402Profile::sample(PositionSample& out) const noexcept {
  out.position = static_cast<double>(position_.value()) * settings_.position_per_unit;
  out.time_ns = sample_time_ns_;
  out.status = statusword_;
  out.flags = kSampleHasTime;
  if (settings_.cia402.map_velocity) {
    out.velocity = velocity_ * settings_.position_per_unit;
    out.flags |= kSampleHasVelocity;
  }
}

std::span<const CanFrame> Cia402Profile::tick_frames(double force) noexcept {
  const double permille =
      std::clamp(force * permille_per_force_, -1.0 * max_permille_, 1.0 * max_permille_);
  const auto torque = static_cast<std::int16_t>(std::lround(permille));
  // RPDO first, then SYNC: the drive applies the torque at this SYNC and samples its position.
  tx_[0] = canopen::rpdo1_frame(settings_.node_id, cia402::kCwEnableOperation, torque);
  tx_[1] = canopen::sync_frame();
  std::size_t n = 2;
  if (master_heartbeat_ticks_ != 0 && tick_++ % master_heartbeat_ticks_ == 0) {
    tx_[n++] =
        canopen::heartbeat_frame(settings_.cia402.master_node_id, canopen::NmtState::kOperational);
  }
  last_sync_ns_.store(base::monotonic_ns(), std::memory_order_relaxed);
  return {tx_.data(), n};
}

std::string Cia402Profile::describe(const CanFault& f, const std::string&) const {
  const std::string node = "can: cia402 node " + std::to_string(settings_.node_id);
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
      return node + ": no heartbeat (" + hex(canopen::kHeartbeatBase + settings_.node_id, 3) +
             ") for " + std::to_string(f.code) + " ticks (heartbeat_timeout_ms " +
             std::to_string(settings_.heartbeat_timeout_ms) + ")";
    default:
      return {};  // the bus's: the device names it
  }
}

}  // namespace hapticd::drivers::can
