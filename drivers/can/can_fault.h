// Why a CAN device latched (docs/drivers/can.md): the kinds of fault the bus and the two
// profiles raise, each with the detail its code carries, and the sentences of the bus's own.
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::drivers::can {

enum class CanFaultKind : std::uint8_t {
  kNone,
  // The bus (transport faults).
  kSocketError,   // code: errno
  kPeerClosed,    // the socketpair's other end went away
  kBusOff,        // the controller left the bus
  kErrorPassive,  // the controller's error counters passed 127
  kRxOverflow,    // frames were lost in the controller
  kTxQueueFull,   // code: ticks in a row the queue refused a frame
  // The drive (device faults).
  kHeartbeatLost,     // code: ticks without a heartbeat
  kEmcy,              // code: error register << 16 | EMCY error code
  kEmcyTruncated,     // code: the frame's length
  kStatuswordFault,   // code: statusword
  kLeftOperation,     // code: statusword (enabled -> something else)
  kNmtStateChanged,   // code: the NMT state the heartbeat reported
  kAxisError,         // code: ODrive axis error
  kAxisStateChanged,  // code: ODrive axis state
};

struct CanFault {
  CanFaultKind kind = CanFaultKind::kNone;
  std::uint32_t code = 0;
  std::uint8_t joint = 0;  // the node that reported it (a drive's kind): device.can.nodes[joint]
};

// RT-safe. Whether `kind` is the bus's (a transport fault) rather than the drive's.
bool is_transport(CanFaultKind kind) noexcept;

// Not RT-safe. The sentence for a fault of the bus on `where` ("can vcan0"); a drive's kind
// (the profile names those) is "WHERE: transport fault".
std::string describe_bus_fault(const CanFault& fault, const std::string& where);

// Not RT-safe. "0x0000002A" (`digits` hex digits).
std::string hex(std::uint32_t v, int digits);

}  // namespace hapticd::drivers::can
