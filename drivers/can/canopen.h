// CiA 301 (CANopen application layer) as far as hapticd uses it, pure: NMT commands, SYNC,
// heartbeat, EMCY, expedited SDO (client and server side), and the cyclic PDOs of the CiA 402
// cyclic-synchronous-torque mapping. The driver and the simulated drive (sim/peers/can/) use
// the same functions, so they cannot disagree about a byte. Nothing here throws on wire data:
// a malformed frame decodes to a named problem, never to a crash.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "drivers/can/can_frame.h"

namespace hapticd::drivers::can::canopen {

// Function codes of the predefined connection set (COB-ID = function + node id).
inline constexpr std::uint32_t kNmtId = 0x000;
inline constexpr std::uint32_t kSyncId = 0x080;
inline constexpr std::uint32_t kEmcyBase = 0x080;
inline constexpr std::uint32_t kTpdo1Base = 0x180;
inline constexpr std::uint32_t kRpdo1Base = 0x200;
inline constexpr std::uint32_t kTpdo2Base = 0x280;
inline constexpr std::uint32_t kSdoTxBase = 0x580;  // server -> client (the drive answers)
inline constexpr std::uint32_t kSdoRxBase = 0x600;  // client -> server (hapticd asks)
inline constexpr std::uint32_t kHeartbeatBase = 0x700;

enum class NmtCommand : std::uint8_t {
  kStart = 0x01,
  kStop = 0x02,
  kEnterPreOperational = 0x80,
  kResetNode = 0x81,
  kResetCommunication = 0x82,
};
enum class NmtState : std::uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7F,
};
std::string_view to_string(NmtState s) noexcept;

CanFrame nmt_command(NmtCommand command, std::uint8_t node) noexcept;
CanFrame sync_frame() noexcept;
CanFrame heartbeat_frame(std::uint8_t node, NmtState state) noexcept;
// The NMT state a heartbeat reports; nothing for a frame that is not one byte with a known state.
std::optional<NmtState> decode_heartbeat(const CanFrame& f) noexcept;
// An NMT command frame addressed to `node` (or to all, node 0); nothing otherwise.
std::optional<NmtCommand> decode_nmt(const CanFrame& f, std::uint8_t node) noexcept;

// --- EMCY ---
struct Emcy {
  std::uint16_t code = 0;           // emergency error code (0x0000: error reset / no error)
  std::uint8_t error_register = 0;  // 0x1001
  std::uint8_t length = 0;          // bytes the frame carried (8 by the standard)
};
CanFrame emcy_frame(std::uint8_t node, std::uint16_t code, std::uint8_t error_register) noexcept;
// Nothing for a frame too short to carry the code and register (a truncated EMCY).
std::optional<Emcy> decode_emcy(const CanFrame& f) noexcept;
// "0x2310 continuous over-current (current, device output side)": the exact code's name where
// CiA 301/402 define one, else its class.
std::string describe_emcy_code(std::uint16_t code);

// --- SDO, expedited transfers only (at most 4 bytes: every object hapticd touches) ---
struct SdoAddress {
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
};
CanFrame sdo_download_request(std::uint8_t node, SdoAddress at, std::uint32_t value,
                              std::uint8_t size) noexcept;
CanFrame sdo_upload_request(std::uint8_t node, SdoAddress at) noexcept;
CanFrame sdo_abort_frame(std::uint8_t node, std::uint32_t base_id, SdoAddress at,
                         std::uint32_t abort_code) noexcept;

// What came back from the server for a request about `expected`.
struct SdoReply {
  enum class Kind {
    kDownloadConfirmed,  // the write was accepted
    kUploadValue,        // value and size hold the object's bytes
    kAbort,              // abort_code says why
    kOtherObject,        // a reply about another index/subindex (stale or foreign): ignore
    kMalformed,          // not a valid expedited reply; problem names what is wrong
  };
  Kind kind = Kind::kMalformed;
  std::uint32_t value = 0;
  std::uint8_t size = 0;  // 1..4 for an upload; 4 when the server did not say
  std::uint32_t abort_code = 0;
  const char* problem = "";
};
SdoReply decode_sdo_reply(const CanFrame& f, SdoAddress expected) noexcept;
// CiA 301's text for an abort code ("object does not exist in the object dictionary").
std::string_view describe_sdo_abort(std::uint32_t abort_code) noexcept;

// The server's view of a request (the simulated drive).
struct SdoRequest {
  enum class Kind { kDownload, kUpload, kAbort, kUnsupported };
  Kind kind = Kind::kUnsupported;
  SdoAddress at;
  std::uint32_t value = 0;
  std::uint8_t size = 0;
};
SdoRequest decode_sdo_request(const CanFrame& f) noexcept;
CanFrame sdo_download_confirm(std::uint8_t node, SdoAddress at) noexcept;
CanFrame sdo_upload_reply(std::uint8_t node, SdoAddress at, std::uint32_t value,
                          std::uint8_t size) noexcept;

// --- the cyclic PDOs of hapticd's CiA 402 mapping (cia402_mapping in cia402.h) ---
// RPDO1: controlword (0x6040, u16), target torque (0x6071, i16 per mille of 0x6076).
CanFrame rpdo1_frame(std::uint8_t node, std::uint16_t controlword, std::int16_t torque) noexcept;
struct Rpdo1 {
  std::uint16_t controlword = 0;
  std::int16_t target_torque = 0;
};
std::optional<Rpdo1> decode_rpdo1(const CanFrame& f) noexcept;  // exactly 4 bytes
// TPDO1: statusword (0x6041, u16), position actual value (0x6064, i32).
CanFrame tpdo1_frame(std::uint8_t node, std::uint16_t statusword, std::int32_t position) noexcept;
struct Tpdo1 {
  std::uint16_t statusword = 0;
  std::int32_t position = 0;
};
std::optional<Tpdo1> decode_tpdo1(const CanFrame& f) noexcept;  // exactly 6 bytes
// TPDO2 (optional): velocity actual value (0x606C, i32).
CanFrame tpdo2_frame(std::uint8_t node, std::int32_t velocity) noexcept;
std::optional<std::int32_t> decode_tpdo2(const CanFrame& f) noexcept;  // exactly 4 bytes

}  // namespace hapticd::drivers::can::canopen
