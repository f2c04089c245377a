#include "sim/peers/gpio/gpio_peer_entry.h"

#include "sim/peers/gpio/gpio_endpoint.h"
#include "sim/peers/gpio/gpio_peer.h"

namespace hapticd::sim::gpio {

PeerEntry peer_entry() {
  PeerEntry e;
  e.driver = "gpio";
  e.make_peer = [](const config::Config& cfg, io::UniqueFd end) {
    return std::unique_ptr<LoopbackPeer>(make_loopback_peer(cfg, std::move(end)));
  };
  e.make_peer_on = [](const config::Config& cfg, const std::string& endpoint) {
    return std::unique_ptr<LoopbackPeer>(make_kernel_peer(cfg, endpoint));
  };
  e.judge_endpoint = &judge_endpoint;
  return e;
}

}  // namespace hapticd::sim::gpio
