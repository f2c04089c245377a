// Where `hapticd peer` may play a simulated device (sim/peers/peer_entry.h, judge_endpoint). A
// simulated drive on a live CAN bus answers beside the real drive at its node id; on a board's
// own GPIO chip or USB device controller it would stand in for hardware a master believes is
// there. So a peer runs on the kernel's own simulations (vcan and vxcan, gpio-sim, dummy_hcd's
// dummy_udc, uhid) and anything else only when told --impersonate-on-real-hardware. Each
// peer's judgement is a pure function of what the kernel says about its endpoint, read apart,
// so a test can feed it every case, real hardware included. Not RT code.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace hapticd::sim {

struct EndpointVerdict {
  enum class Kind : std::uint8_t {
    kSimulated,  // a simulation the kernel provides: the peer may run there
    kReal,       // hardware (or what cannot be told from it): only with the flag
    kUnusable,   // not an endpoint of this driver's peer at all: refused, flag or not
  };
  Kind kind = Kind::kUnusable;
  std::string what;  // the facts in words, for the message
};

// The name of the driver bound to the sysfs device `device` (its `driver` link); "" none.
std::string sysfs_driver_of(const std::filesystem::path& device);

}  // namespace hapticd::sim
