// How many joints one device and one loop drive at most: the fixed size of every per-joint
// array (a device's samples and commands, the kinematics' vectors), so nothing on the RT thread
// allocates for them. Three covers the devices hapticd drives (a delta, a pantograph, an XYZ
// gantry); raising it sizes every such array with it.
#pragma once

#include <cstddef>

namespace hapticd::base {

inline constexpr std::size_t kMaxJoints = 3;

}  // namespace hapticd::base
