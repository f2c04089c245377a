// Where a faulted run may be re-armed from (`hapticctl clear-fault`): the device outside every
// wall. One joint: its coordinate on the wall's side of wall.position. Several joints: the
// task position (the kinematics' forward solution of every joint) on the outside of each wall
// of the scene (n . (x - p) <= 0); an attractor, always in contact by design, does not count.
#pragma once

#include <span>
#include <string>

#include "config/config.h"
#include "drivers/device.h"

namespace hapticd::service {

// Not RT-safe. "" when the device at `samples` (one per joint) may be re-armed, else why not.
std::string rearm_refusal(const config::Config& cfg, std::span<const PositionSample> samples);

}  // namespace hapticd::service
