// The evdev driver's Device on the scripted transport (fake_transport.h), for its unit tests: a
// joystick-like device with ABS_X over [-1000, 1000] mapped onto [-0.05, 0.05] m, force feedback
// with gain and autocenter, at 1 kHz. `adjust` changes the settings before the device is made.
#pragma once

#include <functional>
#include <memory>

#include "drivers/evdev/evdev_device.h"
#include "fake_transport.h"

namespace hapticd::drivers::evdev::testing {

struct Rig {
  explicit Rig(double liveness_ms = 0.0, InputListing listing = {},
               const std::function<void(EvdevSettings&)>& adjust = {}, bool realtime = true) {
    auto s = std::make_shared<EvdevSettings>();
    s->select.name = "x";
    s->axis = {0, Scale::kRange, -0.05, 0.05, false, 0.0};
    s->force_full_scale = 10.0;
    s->autocenter = 0.5;
    s->liveness_ms = liveness_ms;
    if (adjust) adjust(*s);
    settings = s;
    script->facts.name = "scripted";
    script->facts.has_axis = true;
    script->facts.range = {-1000, 1000, 0};
    script->facts.value = -200;  // -0.01 m
    script->facts.ff_constant = script->facts.ff_gain = script->facts.ff_autocenter = true;
    script->facts.ff_effects = 16;
    const bool with_listing = !listing.path.empty();
    device = std::make_unique<EvdevDevice>(
        s,
        [sc = script, listing, with_listing] {
          EvdevDevice::Opened o;
          o.transport = std::make_unique<FakeTransport>(sc);
          if (with_listing) o.listing = listing;
          return o;
        },
        0.001, realtime);
  }
  explicit Rig(const std::function<void(EvdevSettings&)>& adjust) : Rig(0.0, {}, adjust) {}
  void frame(int value, std::int64_t t = 1000) {
    script->events.push_back({ReadStatus::kEvent, {kEvAbs, 0, value, t}});
    script->events.push_back({ReadStatus::kEvent, {kEvSyn, kSynReport, 0, t}});
  }
  std::shared_ptr<const EvdevSettings> settings;
  std::shared_ptr<Script> script = std::make_shared<Script>();
  std::unique_ptr<EvdevDevice> device;
};

}  // namespace hapticd::drivers::evdev::testing
