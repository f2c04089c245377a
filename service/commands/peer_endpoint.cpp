#include "service/commands/peer_endpoint.h"

#include <spdlog/spdlog.h>

#include "config/config_loader.h"
#include "drivers/device.h"

namespace hapticd::service {

void check_peer_endpoint(const sim::PeerEntry& peer, const config::Config& cfg,
                         const std::string& endpoint, const PeerEndpointPolicy& policy) {
  using Kind = sim::EndpointVerdict::Kind;
  const sim::EndpointVerdict v =
      peer.judge_endpoint != nullptr
          ? peer.judge_endpoint(cfg, endpoint)
          : sim::EndpointVerdict{Kind::kReal, "hapticd cannot tell whether " + endpoint +
                                                  " is a simulation for driver " +
                                                  std::string(peer.driver)};
  switch (v.kind) {
    case Kind::kUnusable:
      throw DeviceError("peer: " + v.what);
    case Kind::kReal:
      if (!policy.impersonate_on_real_hardware) {
        throw config::ConfigError(
            {"peer: " + v.what +
             ": a simulated device there would stand in for hardware beside (or instead "
             "of) the real one. Use a simulated endpoint (vcan or vxcan, a gpio-sim chip, "
             "dummy_hcd, uhid), or say --impersonate-on-real-hardware if that is what you "
             "mean"});
      }
      spdlog::warn(
          "peer: {}: impersonating a device on real hardware, as "
          "--impersonate-on-real-hardware says",
          v.what);
      break;
    case Kind::kSimulated:
      spdlog::info("peer: {}", v.what);
      break;
  }
  if (peer.check_endpoint_free != nullptr) peer.check_endpoint_free(cfg, endpoint, policy.listen_s);
}

}  // namespace hapticd::service
