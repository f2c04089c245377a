// The pieces of `hapticd run` that do not depend on its state: announcing the gate and the RT
// set-up, the tick log, the loop's options, and summarising what happened.
#pragma once

#include <memory>
#include <string>

#include "config/config.h"
#include "gate/gate.h"
#include "loop/rt_setup.h"
#include "loop/servo_loop.h"
#include "service/run/device_session.h"
#include "service/run/run_command.h"
#include "service/run/run_summary.h"
#include "service/stop_signals.h"
#include "telemetry/log_writer.h"
#include "telemetry/spsc_ring.h"

namespace hapticd::service {

// The gate's verdict, logged; false when the run must not start (a failing gate that
// safety.gate: warn does not override).
bool announce_gate(const gate::GateReport& report, const config::Config& cfg);
void announce_rt(const loop::RtStatus& rt);

// The tick log and its ring: sized, touched and opened before output is enabled, never on
// the RT thread. A file already at the path is kept (telemetry::keep_previous_log); anything
// that is not a regular file is refused as a configuration error.
struct TickLog {
  std::unique_ptr<telemetry::SpscRing<telemetry::TickRecord>> ring;
  std::unique_ptr<telemetry::LogWriter> writer;
  std::string previous;
};
TickLog open_tick_log(const RunOptions& options, const config::Config& cfg, bool realtime);

loop::LoopOptions loop_options(const RunOptions& options, const config::Config& cfg,
                               const DeviceInfo& info, bool realtime, bool logging);

// A device of several joints: the walls the loop steps in place of the one-joint law, and
// its state (docs/kinematics.md, the loop at several joints). Each wall's passivity observer
// credits the least damping the device has along its normal, as the gate found it (`report`).
struct SceneParts {
  std::unique_ptr<loop::SceneWalls> walls;  // a reload replaces them
  std::unique_ptr<loop::SceneState> state;
};
SceneParts make_scene_parts(const config::Config& cfg, const DeviceInfo& info,
                            const gate::GateReport& report);
// The walls of cfg, each with its observer; a reload's go on from `running`'s: wall i from
// running wall continues[i] (-1: a new wall), or from wall i when `continues` is null
// (docs/operations.md, live reload).
std::unique_ptr<loop::SceneWalls> make_scene_walls(const config::Config& cfg,
                                                   const DeviceInfo& info,
                                                   const gate::GateReport& report,
                                                   const loop::SceneWalls* running = nullptr,
                                                   const std::vector<int>* continues = nullptr);

// The lines as one, each after a "; ": reasons in one refusal.
std::string joined(const std::vector<std::string>& lines);

// `advice`: what to change, after the fault's sentence (direction_report.h).
void summarise_fault(const loop::LoopResult& result, const Device& device, RunSummary& s,
                     const std::string& advice = "");
// Not RT-safe. The loop's sentence for a fault, the device's own after it when it latched one.
std::string describe_fault(const loop::Fault& fault, const Device& device);
// The limits every tick checks a sample against (safety.*, the device's sequence modulus):
// one place for `hapticd run` and `hapticd identify`.
loop::SampleLimits sample_limits(const config::Config& cfg, const DeviceInfo& info, bool realtime);
void summarise_log(const TickLog& log, RunSummary& s);
// The device's state after the run and the run's counters (the loop's, when it ran, and the
// driver's).
void summarise_device(DeviceSession& session, const loop::ServoLoop* loop, RunSummary& s);
void summarise_peer(DeviceSession& session, RunSummary& s);
// Prints the summary (and writes --summary-json); the exit code of the run.
int report(const RunOptions& options, RunSummary& s);

// Whether a stop was requested; logs it and records it in the summary. A SIGHUP is no stop:
// it sets `reload` (the configuration file is read again once the servo runs).
bool stop_requested(SignalWatch& signals, RunSummary& s, const char* when, bool& reload);
// Events for the passivity observer while the loop runs, from the live status the
// supervisor polls: when its energy goes below zero (and back), and how many ticks the
// controller damped since the last report (one report per `every` polls at most).
struct PassivityWatch {
  bool negative = false;
  std::uint64_t damped_reported = 0;
  int polls = 0;
};
void watch_passivity(const loop::LiveStatus& live, PassivityWatch& w, int every);

// Free-running ticks have no real time base, which only a simulated device tolerates.
void check_clock(const config::Config& cfg, bool simulated);
// Configures the device and runs the gate on what it declares (derating cfg's stiffness under
// safety.gate: derate, recorded in the summary); false when the gate refuses.
bool configure_and_gate(config::Config& cfg, DeviceSession& session, RunSummary& s,
                        gate::GateReport& report);

}  // namespace hapticd::service
