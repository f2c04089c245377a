#include "drivers/can/cia402_device.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "drivers/can/cia402.h"

namespace hapticd::drivers::can {
namespace {

using canopen::SdoAddress;
using canopen::SdoReply;
using cia402::PowerState;

std::int64_t now_ms() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1'000'000;
}

std::string hex(std::uint32_t v, int digits) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%0*X", digits, v);
  return buf;
}

}  // namespace

// --- SDO client ---

std::string Cia402Device::sdo_where(SdoAddress at, const char* name) const {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%04X:%02X", at.index, at.subindex);
  return "can: node " + std::to_string(settings_.node_id) + " on " + socket_->description() +
         ": SDO " + buf + " (" + name + ")";
}

void Cia402Device::note_async(const CanFrame& f) {
  if (f.id == canopen::kEmcyBase + settings_.node_id) {
    const auto e = canopen::decode_emcy(f);
    if (e && e->code == 0) return;  // an error reset is good news
    throw DeviceError("can: node " + std::to_string(settings_.node_id) + " sent EMCY " +
                      (e ? canopen::describe_emcy_code(e->code) + " (error register " +
                               hex(e->error_register, 2) + ")"
                         : "truncated to " + std::to_string(f.len) + " bytes"));
  }
}

SdoReply Cia402Device::sdo_exchange(const CanFrame& request, SdoAddress at, const char* name) {
  send_or_throw(request, "an SDO request");
  const std::uint32_t reply_id = canopen::kSdoTxBase + settings_.node_id;
  SdoReply reply;
  const bool answered = await(
      settings_.sdo_timeout_ms,
      [&](const CanFrame& f) {
        if (f.id != reply_id) return false;
        reply = canopen::decode_sdo_reply(f, at);
        return reply.kind != SdoReply::Kind::kOtherObject;
      },
      [&](const CanFrame& f) { note_async(f); });
  if (!answered) {
    throw DeviceError(sdo_where(at, name) + ": no answer within " +
                      std::to_string(settings_.sdo_timeout_ms) +
                      " ms (node id, bitrate, wiring, or the drive is not powered)");
  }
  if (reply.kind == SdoReply::Kind::kAbort) {
    counters_.sdo_aborts.fetch_add(1, std::memory_order_relaxed);
    throw DeviceError(sdo_where(at, name) + ": aborted with " + hex(reply.abort_code, 8) + " " +
                      std::string(canopen::describe_sdo_abort(reply.abort_code)));
  }
  if (reply.kind == SdoReply::Kind::kMalformed) {
    throw DeviceError(sdo_where(at, name) + ": malformed answer: " + reply.problem);
  }
  return reply;
}

std::uint32_t Cia402Device::sdo_read(SdoAddress at, const char* name) {
  const SdoReply r = sdo_exchange(canopen::sdo_upload_request(settings_.node_id, at), at, name);
  if (r.kind != SdoReply::Kind::kUploadValue) {
    throw DeviceError(sdo_where(at, name) + ": answered a read with a write confirmation");
  }
  return r.value;
}

void Cia402Device::sdo_write(SdoAddress at, std::uint32_t value, std::uint8_t size,
                             const char* name) {
  const SdoReply r =
      sdo_exchange(canopen::sdo_download_request(settings_.node_id, at, value, size), at, name);
  if (r.kind != SdoReply::Kind::kDownloadConfirmed) {
    throw DeviceError(sdo_where(at, name) + ": answered a write with a value");
  }
}

// --- lifecycle ---

PowerState Cia402Device::read_state(std::uint16_t& statusword) {
  statusword = static_cast<std::uint16_t>(sdo_read(cia402::kStatusword, "statusword"));
  return cia402::decode_statusword(statusword);
}

std::string Cia402Device::drive_error_text() {
  try {
    const auto code = static_cast<std::uint16_t>(sdo_read(cia402::kErrorCode, "error code"));
    return "error code 0x603F = " + canopen::describe_emcy_code(code);
  } catch (const DeviceError&) {
    return "error code 0x603F unreadable";
  }
}

void Cia402Device::switch_off_and_identify() {
  const std::uint8_t node = settings_.node_id;
  send_or_throw(canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node), "NMT");
  const std::uint32_t type = sdo_read(cia402::kDeviceType, "device type");
  if ((type & 0xFFFF) != cia402::kDeviceProfile402) {
    throw DeviceError("can: node " + std::to_string(node) + " is not a CiA 402 drive (device " +
                      "type 0x1000 = " + hex(type, 8) + ", profile " +
                      std::to_string(type & 0xFFFF) + ")");
  }
  std::uint16_t sw = 0;
  if (read_state(sw) == PowerState::kFault) {
    throw DeviceError("can: node " + std::to_string(node) + " is in Fault (statusword " +
                      cia402::describe_statusword(sw) + ", " + drive_error_text() +
                      "): find the cause, clear it with the drive's tool, and start again");
  }
  // Output off before anything else: "switch on disabled" whatever state it was left in.
  sdo_write(cia402::kControlword, cia402::kCwDisableVoltage, 2, "controlword");
  rated_torque_mnm_ = sdo_read(cia402::kRatedTorque, "rated torque");
  if (rated_torque_mnm_ == 0) {
    throw DeviceError("can: node " + std::to_string(node) + " reports a rated torque 0x6076 of 0");
  }
}

void Cia402Device::write_parameters() {
  const Cia402Settings& c = settings_.cia402;
  sdo_write(cia402::kModesOfOperation,
            static_cast<std::uint8_t>(cia402::kModeCyclicSynchronousTorque), 1,
            "modes of operation");
  const auto shown = static_cast<std::int8_t>(
      sdo_read(cia402::kModesOfOperationDisplay, "modes of operation display"));
  if (shown != cia402::kModeCyclicSynchronousTorque) {
    throw DeviceError("can: node " + std::to_string(settings_.node_id) +
                      " did not take mode 10 (cyclic synchronous torque): 0x6061 shows " +
                      std::to_string(shown));
  }
  const auto cycle_us = static_cast<std::uint32_t>(std::lround(period_s_ * 1e6));
  sdo_write(cia402::kCommunicationCyclePeriod, cycle_us, 4, "communication cycle period");
  sdo_write(cia402::kProducerHeartbeatTime, static_cast<std::uint32_t>(c.heartbeat_producer_ms), 2,
            "producer heartbeat time");
  sdo_write(cia402::kAbortConnectionOption, static_cast<std::uint32_t>(c.comm_loss_reaction), 2,
            "abort connection option code");
  sdo_write(cia402::kTargetTorque, 0, 2, "target torque");
}

void Cia402Device::map_pdos() {
  const bool verify = settings_.cia402.pdo_mapping == PdoMapping::kVerify;
  for (const cia402::MappingEntry& e :
       cia402::pdo_mapping(settings_.node_id, settings_.cia402.map_velocity)) {
    if (!verify) {
      sdo_write(e.at, e.value, e.size, "PDO mapping");
      continue;
    }
    if (!e.final) continue;
    std::uint32_t got = sdo_read(e.at, "PDO mapping");
    std::uint32_t want = e.value;
    if (cia402::is_cob_id(e.at)) {
      got &= cia402::kCobIdCompareMask;
      want &= cia402::kCobIdCompareMask;
    }
    if (got != want) {
      throw DeviceError(sdo_where(e.at, "PDO mapping") + ": is " + hex(got, 8) +
                        ", hapticd needs " + hex(want, 8) +
                        " (set device.can.cia402.pdo_mapping: configure, or map " +
                        "it with the drive's tool; docs/drivers/can.md lists the mapping)");
    }
  }
}

DeviceInfo Cia402Device::on_configure() {
  open_transport();
  switch_off_and_identify();
  write_parameters();
  map_pdos();
  const std::uint32_t vendor = sdo_read(cia402::kVendorId, "vendor id");
  const std::uint8_t node = settings_.node_id;
  // Per mille of the rated torque for one unit of axis force, through the transmission.
  permille_per_force_ = settings_.torque_per_force * 1e6 / rated_torque_mnm_;
  max_permille_ = static_cast<int>(
      std::min(32767.0, std::floor(settings_.max_torque * 1e6 / rated_torque_mnm_)));
  const int hb = settings_.cia402.master_heartbeat_ms;
  master_heartbeat_ticks_ =
      hb == 0 ? 0 : std::max<std::uint32_t>(1, static_cast<std::uint32_t>(hb * 1e-3 / period_s_));
  set_emergency_frames({canopen::rpdo1_frame(node, cia402::kCwEnableOperation, 0),
                        canopen::sync_frame(), canopen::rpdo1_frame(node, cia402::kCwShutdown, 0),
                        canopen::sync_frame(),
                        canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node)});
  DeviceInfo info;
  info.description = "cia402 node " + std::to_string(node) + " on " + socket_->description() +
                     " (vendor " + hex(vendor, 8) + ", rated torque " +
                     std::to_string(rated_torque_mnm_) + " mN m)";
  info.transport_delay_samples = 1;
  return info;
}

void Cia402Device::walk_to_enabled() {
  std::uint16_t sw = 0;
  PowerState state = read_state(sw);
  for (int step = 0; state != PowerState::kOperationEnabled; ++step) {
    const auto cw = cia402::step_towards_enabled(state);
    if (!cw || step > 6) {
      throw DeviceError("can: node " + std::to_string(settings_.node_id) +
                        " cannot be enabled from " + cia402::describe_statusword(sw) +
                        (state == PowerState::kFault ? ", " + drive_error_text() : ""));
    }
    sdo_write(cia402::kControlword, *cw, 2, "controlword");
    const PowerState from = state;
    const std::int64_t deadline = now_ms() + settings_.state_timeout_ms;
    while ((state = read_state(sw)) == from && now_ms() < deadline) {
      socket_->wait_readable(2);  // the drive's own cycle moves it on; ask again shortly
    }
    if (state == from) {
      throw DeviceError("can: node " + std::to_string(settings_.node_id) + ": controlword " +
                        hex(*cw, 4) + " did not move the drive out of " +
                        std::string(cia402::to_string(from)) + " within " +
                        std::to_string(settings_.state_timeout_ms) + " ms (statusword " +
                        cia402::describe_statusword(sw) + ")");
    }
  }
}

void Cia402Device::on_enable() {
  clear_pending();
  fresh_ = false;
  tick_ = 0;
  const std::uint8_t node = settings_.node_id;
  const Cia402Settings& c = settings_.cia402;
  sdo_write(cia402::kTargetTorque, 0, 2, "target torque");
  if (c.drive_watchdog_ms > 0) {
    sdo_write(cia402::kConsumerHeartbeatTime,
              (static_cast<std::uint32_t>(c.master_node_id) << 16) |
                  static_cast<std::uint32_t>(c.drive_watchdog_ms),
              4, "consumer heartbeat time");
  }
  send_or_throw(canopen::nmt_command(canopen::NmtCommand::kStart, node), "NMT start");
  walk_to_enabled();
  heartbeat_seen();
}

void Cia402Device::on_disable() noexcept {
  const std::uint8_t node = settings_.node_id;
  send_quietly(canopen::rpdo1_frame(node, cia402::kCwEnableOperation, 0));
  send_quietly(canopen::sync_frame());
  send_quietly(canopen::rpdo1_frame(node, cia402::kCwShutdown, 0));
  send_quietly(canopen::sync_frame());
  send_quietly(canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node));
  if (!socket_ || settings_.cia402.drive_watchdog_ms == 0) return;
  try {
    // hapticd's heartbeat stops now: the drive must not take that for a lost master.
    sdo_write(cia402::kConsumerHeartbeatTime, 0, 4, "consumer heartbeat time");
  } catch (...) {
    // Best effort: the power stage is already off, and a lost bus is reported elsewhere.
  }
}

void Cia402Device::on_clear_fault() {
  if (!socket_) throw DeviceError("can: the transport is closed");
  clear_pending();
  const std::uint8_t node = settings_.node_id;
  send_or_throw(canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node), "NMT");
  sdo_write(cia402::kControlword, cia402::kCwDisableVoltage, 2, "controlword");
  sdo_write(cia402::kControlword, cia402::kCwFaultReset, 2, "controlword (fault reset)");
  std::uint16_t sw = 0;
  PowerState state = read_state(sw);
  const std::int64_t deadline = now_ms() + settings_.state_timeout_ms;
  while (state == PowerState::kFault && now_ms() < deadline) {
    socket_->wait_readable(2);
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

void Cia402Device::on_tpdo1(const CanSocket::Received& rx) noexcept {
  const auto pdo = canopen::decode_tpdo1(rx.frame);
  if (!pdo) {
    counters_.wrong_length.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  fresh_ = true;
  statusword_ = pdo->statusword;
  position_ = pdo->position;
  sample_time_ns_ = rx.time_ns;
  const PowerState s = cia402::decode_statusword(statusword_);
  if (s == PowerState::kFault || s == PowerState::kFaultReactionActive) {
    raise(CanFaultKind::kStatuswordFault, statusword_);
  } else if (state() == DeviceState::kActive && s != PowerState::kOperationEnabled) {
    raise(CanFaultKind::kLeftOperation, statusword_);
  }
}

void Cia402Device::on_emcy(const CanFrame& f) noexcept {
  const auto e = canopen::decode_emcy(f);
  if (!e) {
    raise(CanFaultKind::kEmcyTruncated, f.len);
  } else if (e->code == 0) {
    counters_.emcy_resets.fetch_add(1, std::memory_order_relaxed);
  } else {
    raise(CanFaultKind::kEmcy, (static_cast<std::uint32_t>(e->error_register) << 16) | e->code);
  }
}

void Cia402Device::on_frame(const CanSocket::Received& rx) noexcept {
  const CanFrame& f = rx.frame;
  const std::uint8_t node = settings_.node_id;
  if (f.extended || f.rtr) {
    counters_.unknown_ids.fetch_add(1, std::memory_order_relaxed);
  } else if (f.id == canopen::kTpdo1Base + node) {
    on_tpdo1(rx);
  } else if (f.id == canopen::kTpdo2Base + node && settings_.cia402.map_velocity) {
    if (const auto v = canopen::decode_tpdo2(f)) {
      velocity_ = *v;
    } else {
      counters_.wrong_length.fetch_add(1, std::memory_order_relaxed);
    }
  } else if (f.id == canopen::kEmcyBase + node) {
    on_emcy(f);
  } else if (f.id == canopen::kHeartbeatBase + node) {
    const auto s = canopen::decode_heartbeat(f);
    if (!s) {
      counters_.wrong_length.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    heartbeat_seen();
    if (state() == DeviceState::kActive && *s != canopen::NmtState::kOperational) {
      raise(CanFaultKind::kNmtStateChanged, static_cast<std::uint32_t>(*s));
    }
  } else {
    counters_.unknown_ids.fetch_add(1, std::memory_order_relaxed);  // late SDO answers too
  }
}

IoStatus Cia402Device::on_read(PositionSample& out) noexcept {
  fresh_ = false;
  const IoStatus drained = drain();
  if (drained != IoStatus::kOk) return drained;
  if (state() == DeviceState::kActive && heartbeat_lost()) {
    return raise(CanFaultKind::kHeartbeatLost, ticks_since_heartbeat());
  }
  if (!fresh_) return IoStatus::kNoNewData;
  out.position = position_ * settings_.position_per_unit;
  out.time_ns = sample_time_ns_;
  out.status = statusword_;
  out.flags = kSampleHasTime;
  if (settings_.cia402.map_velocity) {
    out.velocity = velocity_ * settings_.position_per_unit;
    out.flags |= kSampleHasVelocity;
  }
  return IoStatus::kOk;
}

IoStatus Cia402Device::on_write(double force) noexcept {
  const double permille =
      std::clamp(force * permille_per_force_, -1.0 * max_permille_, 1.0 * max_permille_);
  const auto torque = static_cast<std::int16_t>(std::lround(permille));
  const std::uint8_t node = settings_.node_id;
  // RPDO first, then SYNC: the drive applies the torque at this SYNC and samples its position.
  bool ok = send_rt(canopen::rpdo1_frame(node, cia402::kCwEnableOperation, torque)) &&
            send_rt(canopen::sync_frame());
  if (ok && master_heartbeat_ticks_ != 0 && tick_++ % master_heartbeat_ticks_ == 0) {
    ok = send_rt(
        canopen::heartbeat_frame(settings_.cia402.master_node_id, canopen::NmtState::kOperational));
  }
  if (ok) ok = end_tick_tx();
  return ok ? IoStatus::kOk : pending_fault();
}

std::string Cia402Device::describe(const DeviceFault& f) const {
  const std::string seen = counter_summary();
  return describe_cause(f) + (seen.empty() ? "" : " (also seen on the bus: " + seen + ")");
}

std::string Cia402Device::describe_cause(const DeviceFault& f) const {
  const std::string node = "can: cia402 node " + std::to_string(settings_.node_id);
  switch (fault_kind()) {
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
      return describe_transport(f);
  }
}

}  // namespace hapticd::drivers::can
