// A simulated Falcon (sim/peers/falcon/falcon_peer.h) on a real socketpair with the tests' host
// (socket_falcon_host.h) on the other end, over config/sim-delta.yaml: the delta of the Falcon's
// geometry, driver sim (the peer needs no device.falcon section).
#pragma once

#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "falcon_image.h"
#include "sim/peers/falcon/falcon_peer.h"
#include "socket_falcon_host.h"

namespace hapticd::sim::falcon::testing {

using hapticd::testing::falcon_image_bytes;

inline config::Config sim_delta(std::vector<std::string> sets = {}) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/config/sim-delta.yaml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> overrides;
  for (const std::string& s : sets) overrides.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), path, overrides, HAPTICD_SOURCE_DIR "/config");
}

// A hand of 1 N/m that barely holds the arms (the schema offers no operator "none" here):
inline const std::string kLightHand = "device.sim.operator.stiffness=1";

struct Rig {
  explicit Rig(FalconPeerOptions o = {}, std::vector<std::string> sets = {}, bool pumped = true)
      : cfg(sim_delta(std::move(sets))) {
    auto [host_end, peer_end] = io::seqpacket_pair();
    peer = std::make_unique<FalconPeer>(cfg, std::move(peer_end), o);
    host = std::make_unique<SocketFalconHost>(std::move(host_end), pumped ? peer.get() : nullptr);
  }
  config::Config cfg;
  std::unique_ptr<FalconPeer> peer;
  std::unique_ptr<SocketFalconHost> host;
};

}  // namespace hapticd::sim::falcon::testing
