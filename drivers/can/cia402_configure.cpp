// The CiA 402 drive's start-up over SDO (cia402_profile.h): the SDO client, and configure's
// steps, each object written, read, or - for those a drive may lack - skipped with a notice.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "base/clock.h"
#include "drivers/can/cia402_profile.h"

namespace hapticd::drivers::can {
namespace {

using canopen::SdoAddress;
using canopen::SdoReply;
using cia402::PowerState;

constexpr std::uint32_t kAbortNoObject = 0x06020000;    // CiA 301: object does not exist
constexpr std::uint32_t kAbortNoSubindex = 0x06090011;  // CiA 301: subindex does not exist

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace

std::string Cia402Node::node_name() const {
  return "can: node " + std::to_string(node_.node_id) + " on " + link_.description();
}

// --- SDO client ---

std::string Cia402Node::sdo_where(SdoAddress at, const char* name) const {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%04X:%02X", at.index, at.subindex);
  return node_name() + ": SDO " + buf + " (" + name + ")";
}

void Cia402Node::note_async(const CanFrame& f) {
  if (f.id == canopen::kEmcyBase + node_.node_id) {
    const auto e = canopen::decode_emcy(f);
    if (e && e->code == 0) return;  // an error reset is good news
    if (stopping_) {
      // The stop goes on: the statusword, not the EMCY, says whether the power stage is off,
      // and its watches must still be switched off (docs/drivers/can.md).
      link_.count(CanCounter::kEmcysInStop);
      return;
    }
    throw DeviceError("can: node " + std::to_string(node_.node_id) + " sent EMCY " +
                      (e ? canopen::describe_emcy_code(e->code) + " (error register " +
                               hex(e->error_register, 2) + ")"
                         : "truncated to " + std::to_string(f.len) + " bytes"));
  }
}

SdoReply Cia402Node::sdo_exchange(const CanFrame& request, SdoAddress at, const char* name,
                                  bool may_lack) {
  link_.send(request, "an SDO request");
  const std::uint32_t reply_id = canopen::kSdoTxBase + node_.node_id;
  SdoReply reply;
  const bool answered = link_.await(
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
    link_.count(CanCounter::kSdoAborts);
    if (may_lack && (reply.abort_code == kAbortNoObject || reply.abort_code == kAbortNoSubindex)) {
      return reply;
    }
    throw DeviceError(sdo_where(at, name) + ": aborted with " + hex(reply.abort_code, 8) + " " +
                      std::string(canopen::describe_sdo_abort(reply.abort_code)));
  }
  if (reply.kind == SdoReply::Kind::kMalformed) {
    throw DeviceError(sdo_where(at, name) + ": malformed answer: " + reply.problem);
  }
  return reply;
}

std::optional<std::uint32_t> Cia402Node::sdo_read_optional(SdoAddress at, const char* name) {
  const SdoReply r = sdo_exchange(canopen::sdo_upload_request(node_.node_id, at), at, name, true);
  if (r.kind == SdoReply::Kind::kAbort) return std::nullopt;
  if (r.kind != SdoReply::Kind::kUploadValue) {
    throw DeviceError(sdo_where(at, name) + ": answered a read with a write confirmation");
  }
  return r.value;
}

std::uint32_t Cia402Node::sdo_read(SdoAddress at, const char* name) {
  const SdoReply r = sdo_exchange(canopen::sdo_upload_request(node_.node_id, at), at, name);
  if (r.kind != SdoReply::Kind::kUploadValue) {
    throw DeviceError(sdo_where(at, name) + ": answered a read with a write confirmation");
  }
  return r.value;
}

bool Cia402Node::sdo_write_optional(SdoAddress at, std::uint32_t value, std::uint8_t size,
                                    const char* name) {
  const SdoReply r =
      sdo_exchange(canopen::sdo_download_request(node_.node_id, at, value, size), at, name, true);
  if (r.kind == SdoReply::Kind::kAbort) return false;
  if (r.kind != SdoReply::Kind::kDownloadConfirmed) {
    throw DeviceError(sdo_where(at, name) + ": answered a write with a value");
  }
  return true;
}

void Cia402Node::sdo_write(SdoAddress at, std::uint32_t value, std::uint8_t size,
                           const char* name) {
  const SdoReply r =
      sdo_exchange(canopen::sdo_download_request(node_.node_id, at, value, size), at, name);
  if (r.kind != SdoReply::Kind::kDownloadConfirmed) {
    throw DeviceError(sdo_where(at, name) + ": answered a write with a value");
  }
}

// --- configure ---

PowerState Cia402Node::read_state(std::uint16_t& statusword) {
  statusword = static_cast<std::uint16_t>(sdo_read(cia402::kStatusword, "statusword"));
  return cia402::decode_statusword(statusword);
}

std::string Cia402Node::drive_error_text() {
  try {
    const auto code = static_cast<std::uint16_t>(sdo_read(cia402::kErrorCode, "error code"));
    return "error code 0x603F = " + canopen::describe_emcy_code(code);
  } catch (const DeviceError&) {
    return "error code 0x603F unreadable";
  }
}

void Cia402Node::switch_off_and_identify() {
  const std::uint8_t node = node_.node_id;
  link_.send(canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node), "NMT");
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

// A drive that limits torque below max_torque renders a softer wall than the one the gate
// passed and the configuration promises, saying nothing (the axis goes through it with no
// fault). Refused, with the two ways out: a warning would leave the wall that was asked for
// unrendered, and the gate cannot see a force limit (its saturation warning would be wrong).
void Cia402Node::check_torque_limit() {
  const auto limit = sdo_read_optional(cia402::kMaxTorque, "max torque");
  if (!limit) {
    notices_.push_back(node_name() +
                       ": the drive has no 0x6072 (max torque), so hapticd cannot see whether it "
                       "limits torque below device.can.max_torque (" +
                       number(node_.max_torque) + " N m); check its manual");
    return;
  }
  const double limit_nm = (*limit & 0xFFFF) * 1e-3 * rated_torque_mnm_ * 1e-3;
  if (limit_nm < node_.max_torque * (1.0 - 1e-9)) {
    const double per_force = std::abs(node_.torque_per_force);
    const double force = limit_nm / per_force;
    throw DeviceError(node_name() + ": the drive limits its torque to 0x6072 = " +
                      std::to_string(*limit & 0xFFFF) + " per mille of 0x6076 (" +
                      number(limit_nm) + " N m), below device.can.max_torque " +
                      number(node_.max_torque) + " N m: the wall would give way at " +
                      number(force) + " instead of " + number(node_.max_torque / per_force) +
                      " (axis force) with no fault; raise 0x6072 with the drive's tool, or set "
                      "device.can.max_torque to at most " +
                      number(limit_nm) + " N m");
  }
}

void Cia402Node::select_mode() {
  sdo_write(cia402::kModesOfOperation,
            static_cast<std::uint8_t>(cia402::kModeCyclicSynchronousTorque), 1,
            "modes of operation");
  // Drives switch mode on their own cycle and show it in 0x6061 when done, some ms later.
  const std::int64_t deadline = base::monotonic_ms() + settings_.state_timeout_ms;
  std::int8_t shown = 0;
  while ((shown = static_cast<std::int8_t>(
              sdo_read(cia402::kModesOfOperationDisplay, "modes of operation display"))) !=
             cia402::kModeCyclicSynchronousTorque &&
         base::monotonic_ms() < deadline) {
    link_.wait_readable(2);
  }
  if (shown != cia402::kModeCyclicSynchronousTorque) {
    throw DeviceError("can: node " + std::to_string(node_.node_id) +
                      " did not take mode 10 (cyclic synchronous torque): 0x6061 still shows " +
                      std::to_string(shown) + " after state_timeout_ms " +
                      std::to_string(settings_.state_timeout_ms) + " ms");
  }
}

// 0x1006 and 0x60C2: the cycle, for drives that watch SYNC or interpolate on it.
void Cia402Node::write_cycle_objects() {
  const auto cycle_us = static_cast<std::uint32_t>(std::lround(period_s_ * 1e6));
  has_cycle_period_ = sdo_write_optional(cia402::kCommunicationCyclePeriod, cycle_us, 4,
                                         "communication cycle period");
  if (!has_cycle_period_) {
    notices_.push_back(node_name() +
                       ": the drive has no 0x1006 (communication cycle period; CiA 301 requires "
                       "it of SYNC producers only): not written, so it cannot watch the SYNC "
                       "cycle; its heartbeat consumer (0x1016) still watches hapticd");
  }
  const cia402::InterpolationPeriod ip = cia402::interpolation_period(period_s_);
  if (!sdo_write_optional(cia402::kInterpolationPeriodValue, ip.value, 1,
                          "interpolation time period value")) {
    notices_.push_back(node_name() +
                       ": the drive has no 0x60C2 (interpolation time period): not written; "
                       "drives that need it for cyclic synchronous modes (Nanotec, Delta) have it");
    return;
  }
  sdo_write(cia402::kInterpolationPeriodIndex, static_cast<std::uint8_t>(ip.index), 1,
            "interpolation time period index");
  if (!ip.exact) {
    notices_.push_back(node_name() + ": 0x60C2 = " + std::to_string(ip.value) + " x 10^" +
                       std::to_string(ip.index) +
                       " s, the nearest it can say to T = " + number(period_s_ * 1e6) + " us");
  }
}

void Cia402Node::write_parameters() {
  const Cia402Settings& c = settings_.cia402;
  select_mode();
  write_cycle_objects();
  sdo_write(cia402::kProducerHeartbeatTime, static_cast<std::uint32_t>(c.heartbeat_producer_ms), 2,
            "producer heartbeat time");
  if (c.comm_loss_reaction != cia402::CommLossReaction::kNone &&
      !sdo_write_optional(cia402::kAbortConnectionOption,
                          static_cast<std::uint32_t>(c.comm_loss_reaction), 2,
                          "abort connection option code")) {
    throw DeviceError(
        node_name() +
        ": the drive has no 0x6007 (abort connection option code), which is what tells it to "
        "switch its power stage off when hapticd stops talking (a killed process, a cut "
        "cable): without it the last torque may stay applied. If its manual says it switches "
        "off by itself when its heartbeat consumer (0x1016) times out, set "
        "device.can.cia402.comm_loss_reaction: none");
  }
  sdo_write(cia402::kTargetTorque, 0, 2, "target torque");
}

void Cia402Node::map_pdos() {
  const bool verify = settings_.cia402.pdo_mapping == PdoMapping::kVerify;
  std::map<std::uint16_t, std::uint32_t> cob_ids;  // each PDO's COB-ID as the drive holds it
  for (const cia402::MappingEntry& e :
       cia402::pdo_mapping(node_.node_id, settings_.cia402.map_velocity)) {
    if (!verify && e.cob_id) {
      auto it = cob_ids.find(e.at.index);
      if (it == cob_ids.end()) it = cob_ids.emplace(e.at.index, sdo_read(e.at, "PDO COB-ID")).first;
      const std::uint32_t next = cia402::cob_id_to_write(it->second, e.value);
      if (next != it->second) sdo_write(e.at, next, 4, "PDO COB-ID");
      it->second = next;
      continue;
    }
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

std::string Cia402Node::configure() {
  notices_.clear();
  position_.reset();  // the first TPDO1 of this session sets the base
  switch_off_and_identify();
  check_torque_limit();
  write_parameters();
  map_pdos();
  const std::uint32_t vendor = sdo_read(cia402::kVendorId, "vendor id");
  // Per mille of the rated torque for one unit of axis force, through the transmission.
  permille_per_force_ = node_.torque_per_force * 1e6 / rated_torque_mnm_;
  max_permille_ =
      static_cast<int>(std::min(32767.0, std::floor(node_.max_torque * 1e6 / rated_torque_mnm_)));
  return "cia402 node " + std::to_string(node_.node_id) + " on " + link_.description() +
         " (vendor " + hex(vendor, 8) + ", rated torque " + std::to_string(rated_torque_mnm_) +
         " mN m)";
}

}  // namespace hapticd::drivers::can
