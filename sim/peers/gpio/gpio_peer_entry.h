// The simulated GPIO device's half of the GPIO driver's registration
// (sim/peers/peer_entry.h): the motor driver and encoder on the driver's socketpair, or on
// gpio-sim and the PWM simulator (gpio_peer.h).
#pragma once

#include "sim/peers/peer_entry.h"

namespace hapticd::sim::gpio {

PeerEntry peer_entry();

}  // namespace hapticd::sim::gpio
