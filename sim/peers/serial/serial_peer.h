// The serial driver's simulated device (docs/drivers/serial.md): a board that speaks the
// configured frames (drivers/serial/serial_frame.h) on the driver's loopback socketpair, each
// frame one message. It takes output frames whole wherever the driver's writes cut them, holds
// each joint's force and steps the plant one period per output frame (a device of one joint:
// a SimAxis; of several: the Mechanism of device.kinematics), and answers each with an input
// frame of the encoders. A stream device also speaks while the driver says nothing (before
// enable), from a timer of one period, without moving the plant: the loopback's time is the
// driver's frames, as the other peers keep it.
#pragma once

#include <memory>

#include "config/config.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/loopback_peer.h"

namespace hapticd::sim::serial {

// Throws config::ConfigError for a configuration whose frames the peer cannot play (a status
// field without a fault mask cannot report a fault: that fault is then refused, not thrown).
std::unique_ptr<LoopbackPeer> make_loopback_peer(const config::Config& cfg, io::UniqueFd fd);

}  // namespace hapticd::sim::serial
