#include "service/run/run_support.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iostream>

#include "config/config_loader.h"
#include "gate/gate_report_format.h"
#include "gate/number_format.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "service/run/counters_report.h"
#include "service/run/gate_derate.h"
#include "telemetry/log_path.h"

namespace hapticd::service {
namespace {

using telemetry::SpscRing;
using telemetry::TickRecord;

std::int64_t unix_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

bool announce_gate(const gate::GateReport& report, const config::Config& cfg) {
  if (report.pass && report.workspace) {
    spdlog::info("gate: pass ({} walls, each along its normal over the workspace's {} samples)",
                 report.workspace->walls.size(), report.workspace->samples);
  } else if (report.pass) {
    spdlog::info("gate: pass (b_req {:.4g} N s/m <= {:.4g} allowed, delay {} samples)",
                 report.passivity.required_damping, report.passivity.available_damping,
                 report.delay_samples);
  } else {
    for (const std::string& r : report.reasons) spdlog::error("gate: {}", r);
    if (!gate_allows(report, cfg)) {
      std::cerr << gate::gate_to_text(report, cfg);
      return false;
    }
    spdlog::error(
        "gate: FAILED but safety.gate is 'warn': running a loop that is not proven passive");
  }
  for (const std::string& w : report.warnings) spdlog::warn("gate: {}", w);
  return true;
}

void announce_rt(const loop::RtStatus& rt) {
  spdlog::info("rt: {}{}{}{}{}",
               rt.fifo ? "SCHED_FIFO " + std::to_string(rt.priority) : "SCHED_OTHER",
               rt.memory_locked ? ", memory locked" : ", memory not locked",
               rt.cpu_dma_latency_zero ? ", cpu_dma_latency 0" : "",
               rt.cpu >= 0 ? ", CPU " + std::to_string(rt.cpu) : "",
               rt.others_off_rt_cpu ? " (other threads kept off it)" : "");
  for (const std::string& w : rt.warnings) spdlog::warn("rt: {}", w);
}

TickLog open_tick_log(const RunOptions& options, const config::Config& cfg, bool realtime) {
  TickLog log;
  const bool from_cli = !options.log_path.empty();
  const std::string path = from_cli ? options.log_path : cfg.telemetry.log_path;
  if (path.empty()) return log;
  const std::string where =
      from_cli ? "--log " + path : cfg.locate("telemetry.log") + ": telemetry.log";
  try {
    log.previous = telemetry::keep_previous_log(path);
    log.ring = std::make_unique<SpscRing<TickRecord>>(cfg.telemetry.ring_capacity);
    log.writer = std::make_unique<telemetry::LogWriter>(
        path,
        telemetry::LogHeader{cfg.loop.sample_period_s(), realtime ? unix_now_ns() : 0,
                             realtime ? 0u : 1u, cfg.effective_yaml},
        *log.ring, 512, std::chrono::milliseconds(5),
        realtime ? telemetry::LogWriter::Flush::kEveryPoll
                 : telemetry::LogWriter::Flush::kFullBlocks);
    constexpr std::uint64_t kMb = 1u << 20;
    log.writer->set_rotation({cfg.telemetry.max_segment_mb * kMb, cfg.telemetry.max_total_mb * kMb,
                              [](const std::string& event) { spdlog::info("{}", event); }});
    log.writer->start();
  } catch (const std::exception& e) {
    throw config::ConfigError({where + ": " + e.what()});
  }
  if (!log.previous.empty()) spdlog::info("tick log: the previous log is now {}", log.previous);
  return log;
}

loop::LoopOptions loop_options(const RunOptions& options, const config::Config& cfg,
                               const DeviceInfo& info, bool realtime, bool logging) {
  loop::LoopOptions lo;
  lo.sample = sample_limits(cfg, info, realtime);
  lo.overrun_fault_streak = cfg.loop.overrun_fault_streak;
  lo.wait_for_ring = !realtime && logging;  // a simulation logs every tick
  lo.observer = control::observer_params(cfg, info.transport_delay_samples);
  lo.probe = control::probe_plan(cfg, info.transport_delay_samples);
  lo.refuse_no_motion = cfg.safety.direction_check.on_no_motion == config::NoMotionAction::kRefuse;
  if (options.duration_s) {
    lo.max_ticks = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(*options.duration_s * cfg.loop.rate_hz)));
  }
  return lo;
}

std::unique_ptr<loop::SceneWalls> make_scene_walls(const config::Config& cfg,
                                                   const DeviceInfo& info,
                                                   const gate::GateReport& report,
                                                   const loop::SceneWalls* running,
                                                   const std::vector<int>* continues) {
  auto scene = std::make_unique<control::Scene>(control::make_scene(cfg));
  std::vector<control::ObserverParams> observers;
  for (std::size_t c = 0; c < scene->channels(); ++c) {
    const std::size_t i = scene->wall_of(c);
    control::ObserverParams p = control::observer_params(cfg, info.transport_delay_samples);
    // A wall the device cannot reach (+inf, or no report) is credited nothing: its observer
    // only ever errs towards damping. An attractor's axes are each credited the least damping
    // the device has in any direction (the gate's lambda_min of B_c).
    const double b = report.workspace && i < report.workspace->walls.size()
                         ? report.workspace->walls[i].worst_damping
                         : 0.0;
    p.device_damping = std::isfinite(b) ? b : 0.0;
    observers.push_back(p);
  }
  auto walls = std::make_unique<loop::SceneWalls>(std::move(scene), observers);
  for (std::size_t i = 0; running != nullptr && i < cfg.walls.size(); ++i) {
    const int from =
        continues != nullptr ? (i < continues->size() ? (*continues)[i] : -1) : static_cast<int>(i);
    if (from >= 0 && static_cast<std::size_t>(from) < running->scene->size()) {
      walls->continues[i] = from;
    }
  }
  return walls;
}

SceneParts make_scene_parts(const config::Config& cfg, const DeviceInfo& info,
                            const gate::GateReport& report) {
  SceneParts parts;
  parts.walls = make_scene_walls(cfg, info, report);
  parts.state = std::make_unique<loop::SceneState>(cfg.device.kinematics, *parts.walls,
                                                   cfg.device.max_force.per_joint());
  return parts;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += (out.empty() ? "" : "; ") + l;
  return out;
}

std::string describe_fault(const loop::Fault& fault, const Device& device) {
  std::string f = loop::describe(fault);
  if (device.fault().fault_class != FaultClass::kNone) f += ": " + device.describe_fault();
  return f;
}

loop::SampleLimits sample_limits(const config::Config& cfg, const DeviceInfo& info, bool realtime) {
  return {realtime,
          cfg.loop.period_ns(),
          cfg.safety.stale_fault_ticks,
          cfg.safety.max_speed,
          cfg.safety.sequence_gap_fault,
          info.sequence_modulus};
}

void summarise_fault(const loop::LoopResult& result, const Device& device, RunSummary& s,
                     const std::string& advice) {
  if (result.fault.cause == loop::FaultCause::kNone) return;
  const std::string f = describe_fault(result.fault, device) + advice;
  spdlog::error("fault: {}; zero force commanded, output disabled", f);
  s.faults.push_back(f);
}

void summarise_log(const TickLog& log, RunSummary& s) {
  if (!log.writer) return;
  const telemetry::LogWriter& w = *log.writer;
  s.log_path = w.path();
  s.previous_log = log.previous;
  s.log_records_written = w.records_written();
  s.log_records_dropped = w.records_dropped();
  s.log_records_lost = w.records_lost();
  s.log_io_errors = w.io_errors();
  s.log_segments = w.segments();
  s.log_files_deleted = w.files_deleted();
  s.log_bytes_deleted = w.bytes_deleted();
  if (s.log_records_dropped > 0) {
    spdlog::warn("tick log: the RT ring was full and dropped {} records (marked in the log)",
                 s.log_records_dropped);
  }
  if (s.log_io_errors > 0) {
    // The servo kept running, but the record of the run is incomplete: that is a failure.
    s.faults.push_back("tick log: " + std::to_string(s.log_io_errors) + " write errors lost " +
                       std::to_string(s.log_records_lost) + " records, first: " + w.last_error());
    spdlog::error("{}", s.faults.back());
  }
}

int report(const RunOptions& options, RunSummary& s) {
  if (s.final_output_enabled || s.final_command != 0.0) {
    s.faults.push_back("the device reports output still enabled or a non-zero last command");
  }
  const bool printed = write_stdout(summary_to_text(s));
  if (!options.summary_json_path.empty()) {
    std::ofstream out(options.summary_json_path);
    out << summary_to_json(s).dump(2) << "\n";
    if (!finish_output(out, options.summary_json_path)) return kExitRuntimeFault;
  }
  if (!printed) return kExitRuntimeFault;
  if (s.faults.empty()) return kExitOk;
  // The direction check refused the device before any wall acted: a refusal, as the gate's.
  const bool refused = loop::is_direction_refusal(s.loop.fault.cause) && s.faults.size() == 1;
  return refused ? kExitGateRefused : kExitRuntimeFault;
}

bool stop_requested(SignalWatch& signals, RunSummary& s, const char* when, bool& reload) {
  while (const std::optional<int> sig = signals.take_pending()) {
    if (*sig == SIGHUP) {
      spdlog::info("SIGHUP received {}: the configuration is reloaded once the servo runs", when);
      reload = true;
      continue;
    }
    s.stop_reason = "signal " + signal_name(*sig);
    spdlog::info("{} received {}: output stays disabled", signal_name(*sig), when);
    return true;
  }
  return false;
}

void summarise_device(DeviceSession& session, const loop::ServoLoop* loop, RunSummary& s) {
  const Device& d = session.device();
  s.device_state = std::string(to_string(d.state()));
  s.final_command = d.last_command();
  s.final_output_enabled = d.output_enabled();
  s.counters = read_run_counters(loop, d);
}

void summarise_peer(DeviceSession& session, RunSummary& s) {
  sim::LoopbackPeer* peer = session.peer();
  if (peer == nullptr) return;
  s.loopback = true;
  s.peer_applied_force = peer->applied_force();
  s.peer_output_on = peer->output_on();
  // The peer's plant is one joint's: a device of several has no operator work to report.
  if (session.device().info().joints == 1) s.operator_work_j = peer->plant().operator_work_j();
  if (const std::string e = session.peer_error(); !e.empty()) {
    s.faults.push_back("loopback peer: " + e);
  }
}

void watch_passivity(const loop::LiveStatus& live, PassivityWatch& w, int every) {
  const double e = live.observer_energy_j.load(std::memory_order_relaxed);
  if (e < 0.0 && !w.negative) {
    spdlog::warn(
        "passivity observer: energy {} J, below zero: the loop is putting energy into the hand",
        gate::format_number(e));
  } else if (e >= 0.0 && w.negative) {
    spdlog::info("passivity observer: energy back at {} J", gate::format_number(e));
  }
  w.negative = e < 0.0;
  if (++w.polls < every) return;
  w.polls = 0;
  const std::uint64_t damped = live.damped_ticks.load(std::memory_order_relaxed);
  if (damped > w.damped_reported) {
    spdlog::warn("passivity controller: damped {} ticks ({} in all), energy {} J",
                 damped - w.damped_reported, damped, gate::format_number(e));
    w.damped_reported = damped;
  }
}

void check_clock(const config::Config& cfg, bool simulated) {
  if (cfg.loop.clock == config::ClockMode::kFreerun && !simulated) {
    throw config::ConfigError({cfg.locate("loop.clock") +
                               ": loop.clock: freerun needs a simulated device (device.driver "
                               "sim, or --loopback), got device.driver '" +
                               cfg.device.driver + "'"});
  }
}

bool configure_and_gate(config::Config& cfg, DeviceSession& session, RunSummary& s,
                        gate::GateReport& report) {
  Device& device = session.device();
  device.configure();
  s.device_description = device.info().description;
  s.device_notices = device.notices();
  for (const std::string& n : s.device_notices) spdlog::warn("{}", n);
  const auto joints = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  if (device.info().joints != joints) {
    throw DeviceError(std::string(device.driver_name()) + ": the device drives " +
                      std::to_string(device.info().joints) + " joint(s) but device.kinematics (" +
                      kinematics::kind_name(cfg.device.kinematics.kind) + ") has " +
                      std::to_string(joints));
  }
  if (joints > 1 && cfg.safety.direction_check.mode != config::DirectionCheckMode::kOff) {
    // Said, not skipped: the check pushes one joint and fits one response.
    throw config::ConfigError(
        {cfg.locate("safety.direction_check") +
         ": safety.direction_check: the direction check pushes one joint; a device of " +
         std::to_string(joints) +
         " joints runs with `mode: off` (each joint's sign is then the configuration's: "
         "docs/kinematics.md)"});
  }
  const int declared = session.driver().declared_delay(cfg);
  if (device.info().transport_delay_samples != declared) {
    throw DeviceError(std::string(device.driver_name()) + ": the device declares " +
                      std::to_string(device.info().transport_delay_samples) +
                      " samples of transport delay but its configuration gives " +
                      std::to_string(declared) + "; `hapticd check` would analyse another loop");
  }
  report = gate::evaluate_gate(cfg, declared);
  const gate::GateReport configured = report;
  s.derated = derate_stiffness(cfg, declared, report);
  if (!s.derated.empty()) {
    for (const std::string& r : configured.reasons) spdlog::error("gate: {}", r);
  }
  for (const Derating& d : s.derated) {
    spdlog::warn(
        "gate: DERATED (safety.gate: derate): {} {} N/m fails, running at {} N/m, the largest "
        "that passes",
        d.key, gate::format_number(d.configured), gate::format_number(d.ran));
  }
  s.gate = gate::gate_to_json(report);
  return announce_gate(report, cfg);
}

}  // namespace hapticd::service
