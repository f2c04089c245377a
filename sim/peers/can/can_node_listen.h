// Before `hapticd peer` plays a CAN drive at node N it makes sure no node N is there already:
// two nodes at one id answer the same requests, and a master reads a simulated position while
// a real motor moves. It asks once (CiA 402: an SDO read of 0x1000, the device type, which
// CiA 301 makes every node answer; ODrive: a Get_Encoder_Estimates request) and listens for
// anything the node sends (its heartbeat or boot-up, EMCY, TPDOs and SDO replies; an ODrive's
// heartbeat and answers). Only what the node itself sends counts: a master already sending
// SYNC, RPDOs or torque commands to node N is what the peer is for. Not RT code.
#pragma once

#include <optional>
#include <string>

#include "config/config.h"
#include "drivers/can/can_frame.h"
#include "drivers/can/can_settings.h"

namespace hapticd::sim {

// Pure: whether the node of `s` sent `f`.
bool sent_by_node(const drivers::can::CanFrame& f, const drivers::can::CanSettings& s);
// Pure: the frame in words ("0x701, the heartbeat of node 1 (pre-operational)").
std::string describe_node_frame(const drivers::can::CanFrame& f,
                                const drivers::can::CanSettings& s);
// Pure: the request the peer asks the node with.
drivers::can::CanFrame node_probe(const drivers::can::CanSettings& s);

// Asks the node on `interface` once, then listens for `seconds`: the first frame it sent, or
// nothing. Throws DeviceError when the interface cannot be opened or the request not sent.
std::optional<drivers::can::CanFrame> listen_for_node(const drivers::can::CanSettings& s,
                                                      const std::string& interface, double seconds);

// The peer entry's check_endpoint_free: listen_for_node for `seconds` (logged), and a
// DeviceError naming what was heard.
void check_can_node_free(const config::Config& cfg, const std::string& interface, double seconds);

}  // namespace hapticd::sim
