#include "drivers/can/canopen.h"

#include <array>
#include <cstdio>

namespace hapticd::drivers::can::canopen {
namespace {

// SDO command specifiers (CiA 301 §7.2.4.3): the top three bits say which service.
constexpr std::uint8_t kCsMask = 0xE0;
constexpr std::uint8_t kDownloadRequest = 0x20;  // ccs 1
constexpr std::uint8_t kDownloadConfirm = 0x60;  // scs 3
constexpr std::uint8_t kUploadRequest = 0x40;    // ccs 2 (and scs 2 for the reply)
constexpr std::uint8_t kAbort = 0x80;
constexpr std::uint8_t kExpedited = 0x02;
constexpr std::uint8_t kSizeIndicated = 0x01;

CanFrame sdo_frame(std::uint32_t id, std::uint8_t command, SdoAddress at) noexcept {
  CanFrame f = make_frame(id, 8);
  f.data[0] = command;
  put_u16(f, 1, at.index);
  f.data[3] = at.subindex;
  return f;
}

std::uint8_t expedited_command(std::uint8_t base, std::uint8_t size) noexcept {
  return static_cast<std::uint8_t>(base | ((4 - size) << 2) | kExpedited | kSizeIndicated);
}

SdoAddress address_of(const CanFrame& f) noexcept { return {get_u16(f, 1), f.data[3]}; }

std::uint32_t masked(std::uint32_t value, std::uint8_t size) noexcept {
  return size >= 4 ? value : value & ((1u << (8 * size)) - 1);
}

struct AbortText {
  std::uint32_t code;
  std::string_view text;
};
constexpr std::array kAbortTexts = {
    AbortText{0x05030000, "toggle bit not alternated"},
    AbortText{0x05040000, "SDO protocol timed out"},
    AbortText{0x05040001, "client/server command specifier not valid or unknown"},
    AbortText{0x05040005, "out of memory"},
    AbortText{0x06010000, "unsupported access to an object"},
    AbortText{0x06010001, "attempt to read a write-only object"},
    AbortText{0x06010002, "attempt to write a read-only object"},
    AbortText{0x06020000, "object does not exist in the object dictionary"},
    AbortText{0x06040041, "object cannot be mapped to the PDO"},
    AbortText{0x06040042, "the objects to be mapped would exceed the PDO length"},
    AbortText{0x06040043, "general parameter incompatibility"},
    AbortText{0x06040047, "general internal incompatibility in the device"},
    AbortText{0x06060000, "access failed due to a hardware error"},
    AbortText{0x06070010, "data type does not match, length of service parameter does not match"},
    AbortText{0x06070012, "data type does not match, length of service parameter too high"},
    AbortText{0x06070013, "data type does not match, length of service parameter too low"},
    AbortText{0x06090011, "sub-index does not exist"},
    AbortText{0x06090030, "invalid value for parameter"},
    AbortText{0x06090031, "value of parameter written too high"},
    AbortText{0x06090032, "value of parameter written too low"},
    AbortText{0x06090036, "maximum value is less than minimum value"},
    AbortText{0x060A0023, "resource not available: SDO connection"},
    AbortText{0x08000000, "general error"},
    AbortText{0x08000020, "data cannot be transferred or stored to the application"},
    AbortText{0x08000021, "data cannot be transferred or stored because of local control"},
    AbortText{0x08000022, "data cannot be transferred or stored in the present device state"},
    AbortText{0x08000023, "no object dictionary is present"},
    AbortText{0x08000024, "no data available"},
};

struct EmcyText {
  std::uint16_t code;
  std::uint16_t mask;  // 0xFFFF: this exact code; 0xFF00, 0xF000: a class
  const char* text;
};
// CiA 301 Table 21 and CiA 402's additions; most specific first.
constexpr std::array kEmcyTexts = {
    EmcyText{0x0000, 0xFFFF, "error reset or no error"},
    EmcyText{0x2310, 0xFFFF, "continuous over-current (device output side)"},
    EmcyText{0x2320, 0xFFFF, "short circuit or earth leakage (device output side)"},
    EmcyText{0x3210, 0xFFFF, "DC link over-voltage"},
    EmcyText{0x3220, 0xFFFF, "DC link under-voltage"},
    EmcyText{0x4210, 0xFFFF, "excess temperature in the device"},
    EmcyText{0x4310, 0xFFFF, "excess temperature in the drive"},
    EmcyText{0x5530, 0xFFFF, "flash memory error"},
    EmcyText{0x7305, 0xFFFF, "incremental sensor 1 fault"},
    EmcyText{0x8110, 0xFFFF, "CAN overrun (objects lost)"},
    EmcyText{0x8120, 0xFFFF, "CAN in error passive mode"},
    EmcyText{0x8130, 0xFFFF, "life guard or heartbeat error"},
    EmcyText{0x8140, 0xFFFF, "recovered from bus-off"},
    EmcyText{0x8150, 0xFFFF, "CAN-ID collision"},
    EmcyText{0x8210, 0xFFFF, "PDO not processed due to length error"},
    EmcyText{0x8220, 0xFFFF, "PDO length exceeded"},
    EmcyText{0x8240, 0xFFFF, "unexpected SYNC data length"},
    EmcyText{0x8250, 0xFFFF, "RPDO timeout"},
    EmcyText{0x8611, 0xFFFF, "following error"},
    EmcyText{0x2100, 0xFF00, "current, device input side"},
    EmcyText{0x2200, 0xFF00, "current inside the device"},
    EmcyText{0x2300, 0xFF00, "current, device output side"},
    EmcyText{0x3100, 0xFF00, "mains voltage"},
    EmcyText{0x3200, 0xFF00, "voltage inside the device"},
    EmcyText{0x3300, 0xFF00, "output voltage"},
    EmcyText{0x4100, 0xFF00, "ambient temperature"},
    EmcyText{0x4200, 0xFF00, "device temperature"},
    EmcyText{0x4300, 0xFF00, "drive temperature"},
    EmcyText{0x8100, 0xFF00, "communication"},
    EmcyText{0x8200, 0xFF00, "protocol error"},
    EmcyText{0x8300, 0xFF00, "torque control"},
    EmcyText{0x8400, 0xFF00, "velocity speed controller"},
    EmcyText{0x8500, 0xFF00, "position controller"},
    EmcyText{0x8600, 0xFF00, "positioning controller"},
    EmcyText{0x8700, 0xFF00, "sync controller"},
    EmcyText{0xFF00, 0xFF00, "device specific"},
    EmcyText{0x1000, 0xF000, "generic error"},
    EmcyText{0x2000, 0xF000, "current"},
    EmcyText{0x3000, 0xF000, "voltage"},
    EmcyText{0x4000, 0xF000, "temperature"},
    EmcyText{0x5000, 0xF000, "device hardware"},
    EmcyText{0x6000, 0xF000, "device software"},
    EmcyText{0x7000, 0xF000, "additional modules"},
    EmcyText{0x8000, 0xF000, "monitoring"},
    EmcyText{0x9000, 0xF000, "external error"},
    EmcyText{0xF000, 0xF000, "additional functions"},
};

}  // namespace

std::string_view to_string(NmtState s) noexcept {
  switch (s) {
    case NmtState::kBootUp:
      return "boot-up";
    case NmtState::kStopped:
      return "stopped";
    case NmtState::kOperational:
      return "operational";
    case NmtState::kPreOperational:
      return "pre-operational";
  }
  return "unknown";
}

CanFrame nmt_command(NmtCommand command, std::uint8_t node) noexcept {
  CanFrame f = make_frame(kNmtId, 2);
  f.data[0] = static_cast<std::uint8_t>(command);
  f.data[1] = node;
  return f;
}

CanFrame sync_frame() noexcept { return make_frame(kSyncId, 0); }

CanFrame heartbeat_frame(std::uint8_t node, NmtState state) noexcept {
  CanFrame f = make_frame(kHeartbeatBase + node, 1);
  f.data[0] = static_cast<std::uint8_t>(state);
  return f;
}

std::optional<NmtState> decode_heartbeat(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 1) return std::nullopt;
  switch (f.data[0] & 0x7F) {  // bit 7 is node guarding's toggle bit
    case 0x00:
      return NmtState::kBootUp;
    case 0x04:
      return NmtState::kStopped;
    case 0x05:
      return NmtState::kOperational;
    case 0x7F:
      return NmtState::kPreOperational;
    default:
      return std::nullopt;
  }
}

std::optional<NmtCommand> decode_nmt(const CanFrame& f, std::uint8_t node) noexcept {
  if (f.id != kNmtId || f.rtr || f.len != 2 || (f.data[1] != 0 && f.data[1] != node)) {
    return std::nullopt;
  }
  switch (f.data[0]) {
    case 0x01:
    case 0x02:
    case 0x80:
    case 0x81:
    case 0x82:
      return static_cast<NmtCommand>(f.data[0]);
    default:
      return std::nullopt;
  }
}

CanFrame emcy_frame(std::uint8_t node, std::uint16_t code, std::uint8_t error_register) noexcept {
  CanFrame f = make_frame(kEmcyBase + node, 8);
  put_u16(f, 0, code);
  f.data[2] = error_register;
  return f;
}

std::optional<Emcy> decode_emcy(const CanFrame& f) noexcept {
  if (f.rtr || f.len < 3) return std::nullopt;
  return Emcy{get_u16(f, 0), f.data[2], f.len};
}

std::string describe_emcy_code(std::uint16_t code) {
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%04X", code);
  for (const EmcyText& t : kEmcyTexts) {
    if ((code & t.mask) == t.code) return std::string(hex) + " " + t.text;
  }
  return std::string(hex) + " (no CiA 301 class)";
}

CanFrame sdo_download_request(std::uint8_t node, SdoAddress at, std::uint32_t value,
                              std::uint8_t size) noexcept {
  const std::uint8_t n = size < 1 ? 1 : size > 4 ? 4 : size;
  CanFrame f = sdo_frame(kSdoRxBase + node, expedited_command(kDownloadRequest, n), at);
  put_u32(f, 4, masked(value, n));
  return f;
}

CanFrame sdo_upload_request(std::uint8_t node, SdoAddress at) noexcept {
  return sdo_frame(kSdoRxBase + node, kUploadRequest, at);
}

CanFrame sdo_abort_frame(std::uint8_t node, std::uint32_t base_id, SdoAddress at,
                         std::uint32_t abort_code) noexcept {
  CanFrame f = sdo_frame(base_id + node, kAbort, at);
  put_u32(f, 4, abort_code);
  return f;
}

SdoReply decode_sdo_reply(const CanFrame& f, SdoAddress expected) noexcept {
  SdoReply r;
  if (f.rtr || f.len != 8) {
    r.problem = "an SDO reply must carry 8 bytes";
    return r;
  }
  const SdoAddress at = address_of(f);
  if (at.index != expected.index || at.subindex != expected.subindex) {
    r.kind = SdoReply::Kind::kOtherObject;
    return r;
  }
  const std::uint8_t cs = f.data[0];
  if (cs == kAbort) {
    r.kind = SdoReply::Kind::kAbort;
    r.abort_code = get_u32(f, 4);
  } else if (cs == kDownloadConfirm) {
    r.kind = SdoReply::Kind::kDownloadConfirmed;
  } else if ((cs & kCsMask) == kUploadRequest && (cs & kExpedited) != 0) {
    r.kind = SdoReply::Kind::kUploadValue;
    r.size = (cs & kSizeIndicated) != 0 ? static_cast<std::uint8_t>(4 - ((cs >> 2) & 3)) : 4;
    r.value = masked(get_u32(f, 4), r.size);
  } else if ((cs & kCsMask) == kUploadRequest) {
    r.problem = "the server started a segmented upload (hapticd reads only expedited objects)";
  } else {
    r.problem = "an unknown SDO server command specifier";
  }
  return r;
}

std::string_view describe_sdo_abort(std::uint32_t abort_code) noexcept {
  for (const AbortText& t : kAbortTexts) {
    if (t.code == abort_code) return t.text;
  }
  return "an abort code CiA 301 does not define (device specific)";
}

SdoRequest decode_sdo_request(const CanFrame& f) noexcept {
  SdoRequest r;
  if (f.rtr || f.len != 8) return r;
  r.at = address_of(f);
  const std::uint8_t cs = f.data[0];
  if ((cs & kCsMask) == kDownloadRequest && (cs & kExpedited) != 0) {
    r.kind = SdoRequest::Kind::kDownload;
    r.size = (cs & kSizeIndicated) != 0 ? static_cast<std::uint8_t>(4 - ((cs >> 2) & 3)) : 4;
    r.value = masked(get_u32(f, 4), r.size);
  } else if (cs == kUploadRequest) {
    r.kind = SdoRequest::Kind::kUpload;
  } else if (cs == kAbort) {
    r.kind = SdoRequest::Kind::kAbort;
  }
  return r;
}

CanFrame sdo_download_confirm(std::uint8_t node, SdoAddress at) noexcept {
  return sdo_frame(kSdoTxBase + node, kDownloadConfirm, at);
}

CanFrame sdo_upload_reply(std::uint8_t node, SdoAddress at, std::uint32_t value,
                          std::uint8_t size) noexcept {
  const std::uint8_t n = size < 1 ? 1 : size > 4 ? 4 : size;
  CanFrame f = sdo_frame(kSdoTxBase + node, expedited_command(kUploadRequest, n), at);
  put_u32(f, 4, masked(value, n));
  return f;
}

CanFrame rpdo1_frame(std::uint8_t node, std::uint16_t controlword, std::int16_t torque) noexcept {
  CanFrame f = make_frame(kRpdo1Base + node, 4);
  put_u16(f, 0, controlword);
  put_u16(f, 2, static_cast<std::uint16_t>(torque));
  return f;
}

std::optional<Rpdo1> decode_rpdo1(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 4) return std::nullopt;
  return Rpdo1{get_u16(f, 0), static_cast<std::int16_t>(get_u16(f, 2))};
}

CanFrame tpdo1_frame(std::uint8_t node, std::uint16_t statusword, std::int32_t position) noexcept {
  CanFrame f = make_frame(kTpdo1Base + node, 6);
  put_u16(f, 0, statusword);
  put_u32(f, 2, static_cast<std::uint32_t>(position));
  return f;
}

std::optional<Tpdo1> decode_tpdo1(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 6) return std::nullopt;
  return Tpdo1{get_u16(f, 0), static_cast<std::int32_t>(get_u32(f, 2))};
}

CanFrame tpdo2_frame(std::uint8_t node, std::int32_t velocity) noexcept {
  CanFrame f = make_frame(kTpdo2Base + node, 4);
  put_u32(f, 0, static_cast<std::uint32_t>(velocity));
  return f;
}

std::optional<std::int32_t> decode_tpdo2(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 4) return std::nullopt;
  return static_cast<std::int32_t>(get_u32(f, 0));
}

}  // namespace hapticd::drivers::can::canopen
