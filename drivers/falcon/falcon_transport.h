// The Falcon driver's transport seam: the FT232's requests and bulk data for the firmware load
// and homing (FtdiLink, not RT), and each tick's packet out and what came in (RT). Implemented
// over the loopback socketpair with the simulated Falcon (socket_link.h) and over libusb for
// the device.
#pragma once

#include <cstdint>
#include <string>

#include "drivers/falcon/falcon_protocol.h"
#include "drivers/falcon/ftdi_link.h"

namespace hapticd::drivers::falcon {

enum class TransportIo : std::uint8_t {
  kOk,     // send: handed on; receive: whatever arrived is in the stream (maybe nothing)
  kEmpty,  // send: the previous packet had not gone out yet: it is replaced by this one (libusb),
           // or this one is dropped (a socket whose peer does not read); counted, and a device
           // that gets no packet answers none: the liveness bound faults it
  kError,  // the transport failed: error() says why
};

class FalconTransport : public FtdiLink {
 public:
  // Not RT-safe. One line naming the device and the way to it.
  virtual std::string describe() const = 0;
  // RT-safe: called every tick. Hands one packet to the device without blocking.
  virtual TransportIo send(const Packet& p) noexcept = 0;
  // RT-safe: called every tick. Everything that arrived since the last call, into `stream`.
  virtual TransportIo receive(PacketStream& stream) noexcept = 0;
  // RT-safe. CLOCK_MONOTONIC ns when the newest data that receive() handed on arrived at the
  // host (0: none yet): a packet's time, as the firmware answers at once.
  virtual std::int64_t received_ns() const noexcept = 0;
  // RT-safe. The errno of the failure (ENODEV: the device is gone).
  virtual int error() const noexcept = 0;
  // Not RT-safe. From here on the ticks' send and receive carry the exchange (the FtdiLink
  // calls are for the load and homing before it): where the transport needs threads for
  // that, they start here, before the first tick.
  virtual void start() {}
  // Async-signal-safe: `p` written on an already-open descriptor, where the transport has one
  // (a crash handler's zero torque); nothing otherwise.
  virtual void emergency(const Packet& p) noexcept = 0;
};

}  // namespace hapticd::drivers::falcon
