// The configurations the gate's tests analyse, with the numbers their closed forms use.
#pragma once

#include "config/config.h"

namespace hapticd::gate::test {

inline config::Config demo() {  // the numbers of config/sim.yaml
  config::Config c;
  c.source_name = "test";
  c.loop.rate_hz = 1000;
  c.device.mass = 0.1;
  c.device.damping = 2.0;
  c.wall.stiffness = 2000;
  c.wall.damping = 0.2;
  c.safety.passivity_margin = 0.1;
  return c;
}

inline config::Config example1(bool with_coupling) {  // Naghshtabrizi & Hespanha's Example 1
  config::Config c = demo();
  c.loop.rate_hz = 50;
  c.device.damping = 10;
  c.wall.stiffness = 1000;
  c.wall.damping = 20;
  c.safety.passivity_margin = 0.0;
  if (with_coupling) {
    c.wall.coupling = {true, {0.1, -0.0752, 0.0016, -0.0101}, {1, -1.8407, 0.8444, -0.0037}};
  }
  return c;
}

}  // namespace hapticd::gate::test
