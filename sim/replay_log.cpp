#include "sim/replay_log.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "config/config_loader.h"
#include "telemetry/log_reader.h"
#include "telemetry/log_set.h"

namespace hapticd::sim {
namespace {

// The replay operator imposes one position per sample period: a log with a hole in its time
// base would replay a different motion than the one recorded, so it is refused.
void check_contiguous(const telemetry::LogContents& log, const std::string& where,
                      const std::string& path) {
  if (log.dropped_records > 0) {
    throw config::ConfigError({where + path + " is missing " + std::to_string(log.dropped_records) +
                               " records (dropped while logging); replay needs every tick"});
  }
  if (!log.skipped.empty()) {
    throw config::ConfigError({where + path + ": " + log.skipped.front().reason +
                               "; the damaged stretch leaves a gap, replay needs every tick"});
  }
  const auto period_ns = std::llround(log.header.sample_period_s * 1e9);
  const telemetry::TickRecord* prev = nullptr;
  for (const telemetry::TickRecord& b : log.records) {
    if (b.marker != telemetry::kMarkerNone) continue;  // an event, not a tick
    if (prev == nullptr) {
      prev = &b;
      continue;
    }
    const telemetry::TickRecord& a = *prev;
    prev = &b;
    if (b.tick != a.tick + 1 || std::llabs(b.scheduled_ns - a.scheduled_ns - period_ns) > 1) {
      throw config::ConfigError(
          {where + path + " has a gap after tick " + std::to_string(a.tick) +
           " (next record: tick " + std::to_string(b.tick) + ", " +
           std::to_string((b.scheduled_ns - a.scheduled_ns) * 1e-6) +
           " ms later): the loop missed periods; replay needs one position per period"});
    }
  }
}

}  // namespace

std::vector<double> load_replay_positions(const config::Config& cfg) {
  const std::string& path = cfg.device.sim.op.replay_log;
  const std::string where = cfg.locate("device.sim.operator.log") + ": device.sim.operator.log: ";
  telemetry::LogContents log;
  try {
    log = telemetry::read_log_set(path).contents;  // every segment of a rotated log
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
  check_contiguous(log, where, path);
  if (!log.trailing_reason.empty()) {
    spdlog::warn("replay: {}: {}: replaying the {} ticks before it", path, log.trailing_reason,
                 log.records.size());
  }
  std::vector<double> x;
  x.reserve(log.records.size());
  for (const telemetry::TickRecord& r : log.records) {
    if (r.marker == telemetry::kMarkerNone) x.push_back(r.position);
  }
  return x;
}

}  // namespace hapticd::sim
