#include "sim/peers/evdev/evdev_peer_entry.h"

#include "sim/peers/evdev/evdev_peer.h"

namespace hapticd::sim::evdev {

PeerEntry peer_entry() {
  PeerEntry e;
  e.driver = "evdev";
  e.make_peer = [](const config::Config& cfg, io::UniqueFd end) -> std::unique_ptr<LoopbackPeer> {
    // Over the socketpair the device holds each answer as long as the kernel's driver and the
    // USB link would: the delay the driver declares.
    const int delay = drivers::evdev::declared_delay_samples(drivers::evdev::evdev_settings(cfg),
                                                             cfg.loop.sample_period_s());
    return std::make_unique<SocketEvdevPeer>(cfg, std::move(end), delay);
  };
  return e;
}

}  // namespace hapticd::sim::evdev
