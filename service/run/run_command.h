// `hapticd run`: the main job. Gate, enable, loop until the duration ends, a signal or a
// fault; then zero force, disable output, flush the log, summarise.
#pragma once

#include <optional>
#include <string>

#include "service/config_source.h"
#include "service/stop_signals.h"

namespace hapticd::service {

struct RunOptions {
  ConfigOptions config;
  std::optional<double> duration_s;  // none: until SIGINT/SIGTERM
  std::string log_path;              // overrides telemetry.log
  std::string summary_json_path;
  bool loopback = false;    // drive the configured driver against its simulated peer
  std::string socket_path;  // the control socket; "" for none
  // A fault latches and waits for `clear-fault` (or a stop) instead of ending the run.
  bool on_fault_hold = false;
};

// Returns the process exit code (docs/operations.md). A stop signal taken from `signals` at any
// moment before output is enabled means output is never enabled (exit 0, 0 ticks); SIGHUP
// reloads the configuration file (with the same --set arguments) through the gate.
int run_command(const RunOptions& options, SignalWatch& signals);

}  // namespace hapticd::service
