// What differs between the two kinds of drive the CAN driver speaks to (device.can.profile):
// the start-up and shut-down sequences, what each received frame means, and the frames of
// each tick, for every node of device.can.nodes on the bus (joint i is node i). The Device
// (can_device.h) owns the lifecycle, the draining of the socket, the TX accounting, the heartbeat
// watch and the fault policy, and calls these; a profile speaks on the bus through the device's
// CanLink, given at construction (it outlives the profile). Configuration-time calls throw
// DeviceError; the RT calls never block, allocate, lock, log or throw.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "drivers/can/can_fault.h"
#include "drivers/can/can_link.h"
#include "drivers/can/can_settings.h"
#include "drivers/device.h"

namespace hapticd::drivers::can {

// What one frame from the drive meant, for the device to act on.
struct FrameMeaning {
  bool sample = false;     // a new position sample (CanProfile::sample reads it)
  bool heartbeat = false;  // the drive's heartbeat: it is alive
  std::uint8_t joint = 0;  // whose: the node's index in device.can.nodes
  CanFault fault;          // a fault the drive reported (kind kNone: none; its joint set)
};

class CanProfile {
 public:
  virtual ~CanProfile() = default;

  // Not RT-safe. The link is open: identify every drive and prepare it, output off; what the
  // gate analyses (its joints: one per node).
  virtual DeviceInfo configure() = 0;
  // Not RT-safe. Output on with zero torque on every node (an enable left half done, some
  // nodes on, is undone by disable).
  virtual void enable() = 0;
  // Not RT-safe, never throws. Zero torque and output off on every node, once per enable
  // however often it is asked; `latched` is the fault the device holds (kind kNone: none).
  virtual void disable(const CanFault& latched) noexcept = 0;
  // Not RT-safe. Every drive's own fault reset, confirmed.
  virtual void clear_fault() = 0;
  // Not RT-safe, never throws. Ends what writes to the socket on its own (before it closes).
  virtual void close() noexcept = 0;
  // Not RT-safe, valid from configure on (Device::notices).
  virtual std::vector<std::string> notices() const = 0;

  // RT-safe: called every tick, for each frame received. `active`: output is enabled.
  virtual FrameMeaning on_frame(const CanSocket::Received& rx, bool active) noexcept = 0;
  // RT-safe: called every tick each joint's frames meant a sample. Its newest one, in axis
  // units.
  virtual void sample(std::size_t joint, PositionSample& out) const noexcept = 0;
  // RT-safe: called every tick. The frames that carry each joint's force (N or N m; one per
  // node), in order.
  virtual std::span<const CanFrame> tick_frames(std::span<const double> forces) noexcept = 0;
  // Not RT-safe. The sentence for a fault a drive reported (fault.joint's), naming the node;
  // "" for the bus's own (the device names those). `bus` is the link's description.
  virtual std::string describe(const CanFault& fault, const std::string& bus) const = 0;
};

// keeper_priority: SCHED_FIFO priority of the thread that keeps SYNC going during a stop (the
// loop's; 0: none asked).
std::unique_ptr<CanProfile> make_cia402_profile(const CanSettings& s, double sample_period_s,
                                                int keeper_priority, CanLink& link);
std::unique_ptr<CanProfile> make_odrive_profile(const CanSettings& s, double sample_period_s,
                                                CanLink& link);

}  // namespace hapticd::drivers::can
