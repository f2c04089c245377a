#include "service/device_factory.h"

#include <cmath>

#include "config/config_loader.h"
#include "sim/sim_device.h"
#include "telemetry/log_reader.h"

namespace hapticd::service {

std::vector<double> load_replay_positions(const config::Config& cfg) {
  const std::string& path = cfg.device.sim.op.replay_log;
  const std::string where = cfg.source_name + ": device.sim.operator.log: ";
  telemetry::LogContents log;
  try {
    log = telemetry::read_log(path);
  } catch (const std::exception& e) {
    throw config::ConfigError({where + e.what()});
  }
  const double t = cfg.loop.sample_period_s();
  if (std::abs(log.header.sample_period_s - t) > 1e-12 * t) {
    throw config::ConfigError(
        {where + path + " was recorded at T = " + std::to_string(log.header.sample_period_s) +
         " s but loop.rate_hz gives T = " + std::to_string(t) + " s"});
  }
  if (log.records.empty()) throw config::ConfigError({where + path + " holds no tick records"});
  std::vector<double> x;
  x.reserve(log.records.size());
  for (const telemetry::TickRecord& r : log.records) x.push_back(r.position);
  return x;
}

std::unique_ptr<Device> make_device(const config::Config& cfg) {
  switch (cfg.device.driver) {
    case config::DriverKind::kSim: {
      std::vector<double> replay;
      if (cfg.device.sim.op.kind == config::OperatorSpec::Kind::kReplay) {
        replay = load_replay_positions(cfg);
      }
      try {
        return std::make_unique<sim::SimDevice>(cfg.device, cfg.loop.sample_period_s(),
                                                std::move(replay));
      } catch (const std::invalid_argument& e) {
        throw config::ConfigError({cfg.source_name + ": device.sim: " + e.what()});
      }
    }
    case config::DriverKind::kHid:
    case config::DriverKind::kCan:
    case config::DriverKind::kGpio:
      break;
  }
  throw DeviceError("device.driver: " + config::driver_name(cfg.device.driver) +
                    ": this build has no such driver yet (only 'sim'); `hapticd check` analyses "
                    "it with its declared transport delay, but `run` cannot open it");
}

}  // namespace hapticd::service
