#include "wiring/sim_driver.h"

#include <stdexcept>
#include <vector>

#include "config/config_loader.h"
#include "sim/replay_log.h"
#include "sim/sim_device.h"

namespace hapticd::wiring {
namespace {

int no_delay(const drivers::DriverContext&) { return 0; }  // in-process: written at k, acts from k

Loopback sim_loopback(const config::Config& cfg) {
  std::vector<double> replay;
  if (cfg.device.sim.op.kind == config::OperatorSpec::Kind::kReplay) {
    replay = sim::load_replay_positions(cfg);
  }
  std::unique_ptr<sim::SimDevice> device;
  try {
    device =
        std::make_unique<sim::SimDevice>(cfg.device, cfg.loop.sample_period_s(), std::move(replay));
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError({cfg.locate("device.sim") + ": device.sim: " + e.what()});
  }
  auto peer = std::make_unique<sim::SimSelfPeer>(*device);
  return {std::move(device), std::move(peer)};
}

// Only the simulated motor itself can be wired the other way round.
drivers::ForceReversal force_reversal(const config::Config& cfg) {
  const bool reversed = cfg.device.sim.force_reversed;
  return {"device.sim.force_reversed", reversed ? "true" : "false", reversed ? "false" : "true"};
}

}  // namespace

DriverEntry sim_driver() {
  DriverEntry e;
  e.name = "sim";
  e.summary = "the exact simulated device, in-process (device.sim)";
  e.declared_delay = &no_delay;
  e.force_reversal = &force_reversal;
  e.peer.driver = "sim";
  e.make_in_process = &sim_loopback;
  return e;
}

}  // namespace hapticd::wiring
