#include "drivers/can/can_fault.h"

#include <cstdio>
#include <cstring>

namespace hapticd::drivers::can {

bool is_transport(CanFaultKind kind) noexcept {
  switch (kind) {
    case CanFaultKind::kSocketError:
    case CanFaultKind::kPeerClosed:
    case CanFaultKind::kBusOff:
    case CanFaultKind::kErrorPassive:
    case CanFaultKind::kRxOverflow:
    case CanFaultKind::kTxQueueFull:
      return true;
    default:
      return false;
  }
}

std::string describe_bus_fault(const CanFault& f, const std::string& where) {
  switch (f.kind) {
    case CanFaultKind::kSocketError:
      return where + ": the socket failed: " + std::strerror(static_cast<int>(f.code)) +
             " (errno " + std::to_string(f.code) + ")";
    case CanFaultKind::kPeerClosed:
      return where + ": the other end of the connection went away";
    case CanFaultKind::kBusOff:
      return where +
             ": the CAN controller went bus-off (too many errors: wiring, termination, "
             "bitrate, or a node that is off); nothing reaches the drive";
    case CanFaultKind::kErrorPassive:
      return where + ": the CAN controller went error-passive (error counter above 127)";
    case CanFaultKind::kRxOverflow:
      return where + ": the CAN controller lost received frames (overflow)";
    case CanFaultKind::kTxQueueFull:
      return where + ": the TX queue refused frames (ENOBUFS) " + std::to_string(f.code) +
             " ticks in a row: the bus does not carry what the loop sends";
    default:
      return where + ": transport fault";
  }
}

std::string hex(std::uint32_t v, int digits) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%0*X", digits, v);
  return buf;
}

}  // namespace hapticd::drivers::can
