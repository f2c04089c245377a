#include "sim/peers/can/can_peer_entry.h"

#include <stdexcept>
#include <vector>

#include "config/config_loader.h"
#include "drivers/can/can_settings.h"
#include "drivers/can/canopen.h"
#include "drivers/can/odrive_protocol.h"
#include "sim/peers/can/can_bus_peer.h"
#include "sim/peers/can/can_endpoint.h"
#include "sim/peers/can/can_node_listen.h"
#include "sim/peers/can/cia402_peer.h"
#include "sim/peers/can/odrive_peer.h"

namespace hapticd::sim {
namespace {

namespace can = drivers::can;

// The frames the simulated drives of cfg's profile, one per node, need to see on a shared bus.
std::vector<can::IdFilter> peer_filters(const config::Config& cfg) {
  const can::CanSettings& s = can::can_settings(cfg);
  std::vector<can::IdFilter> filters;
  if (s.profile != can::Profile::kOdrive) {
    filters = {{can::canopen::kNmtId},
               {can::canopen::kSyncId},
               {can::canopen::kHeartbeatBase + s.cia402.master_node_id}};
  }
  for (const can::CanNode& node : s.nodes) {
    const std::uint32_t n = node.node_id;
    if (s.profile == can::Profile::kOdrive) {
      filters.push_back({can::odrive::frame_id(n, 0), 0x7E0});  // the node's 32 command ids
    } else {
      filters.push_back({can::canopen::kRpdo1Base + n});
      filters.push_back({can::canopen::kSdoRxBase + n});
    }
  }
  return filters;
}

std::unique_ptr<LoopbackPeer> loopback_peer(const config::Config& cfg, io::UniqueFd end) {
  // In the same process the simulated drive's clock is its protocol trigger (SYNC, the
  // encoder request) in real-time runs too: its heartbeats and watchdogs count those, so a
  // host that holds every thread up (sim/peers/peer_runner.h) cannot make it see a lost
  // master. On a real interface it keeps wall-clock watchdogs (peer_on).
  return make_can_peer(cfg, can::CanSocket::adopt(std::move(end), "loopback peer"), false);
}

std::unique_ptr<LoopbackPeer> peer_on(const config::Config& cfg, const std::string& endpoint) {
  return make_can_peer(cfg, can::CanSocket::open_interface(endpoint, peer_filters(cfg), false),
                       true);
}

}  // namespace

PeerEntry can_peer_entry() {
  PeerEntry e;
  e.driver = "can";
  e.make_peer = &loopback_peer;
  e.make_peer_on = &peer_on;
  e.judge_endpoint = &judge_can_endpoint;
  e.check_endpoint_free = &check_can_node_free;
  return e;
}

std::unique_ptr<LoopbackPeer> make_can_peer(const config::Config& cfg,
                                            drivers::can::CanSocket socket, bool realtime) {
  try {
    if (can::can_settings(cfg).nodes.size() > 1) {
      return std::make_unique<CanBusPeer>(cfg, std::move(socket), realtime);
    }
    return make_can_drive(cfg, std::move(socket), realtime, {});
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError({cfg.locate("device.sim") + ": device.sim: " + e.what()});
  }
}

std::unique_ptr<CanPeerBase> make_can_drive(const config::Config& cfg,
                                            drivers::can::CanSocket socket, bool realtime,
                                            const SharedJoint& joint) {
  if (can::can_settings(cfg).profile == can::Profile::kOdrive) {
    return std::make_unique<OdrivePeer>(cfg, std::move(socket), realtime, joint);
  }
  return std::make_unique<Cia402Peer>(cfg, std::move(socket), realtime, joint);
}

}  // namespace hapticd::sim
