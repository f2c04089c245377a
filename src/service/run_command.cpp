#include "service/run_command.h"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include "config/config_loader.h"
#include "control/controller.h"
#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "loop/servo_loop.h"
#include "service/device_factory.h"
#include "service/exit_codes.h"
#include "service/run_summary.h"
#include "service/run_threads.h"
#include "sim/sim_device.h"
#include "telemetry/log_writer.h"

namespace hapticd::service {
namespace {

using telemetry::SpscRing;
using telemetry::TickRecord;

std::int64_t unix_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The gate's verdict, logged; false when the run must not start.
bool announce_gate(const gate::GateReport& report, const config::Config& cfg) {
  if (report.pass) {
    spdlog::info("gate: pass (b_req {:.4g} N s/m <= {:.4g} allowed, delay {} samples)",
                 report.passivity.required_damping, report.passivity.available_damping,
                 report.delay_samples);
  } else {
    for (const std::string& r : report.reasons) spdlog::error("gate: {}", r);
    if (cfg.safety.gate == config::GateMode::kEnforce) {
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

// Opens the tick log; an existing file at the path is kept as PATH.1 rather than truncated
// (the log of a run that faulted is what a person reads next).
std::unique_ptr<telemetry::LogWriter> open_log(const std::string& path, const config::Config& cfg,
                                               bool realtime, SpscRing<TickRecord>& ring) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) std::filesystem::rename(path, path + ".1", ec);
  try {
    auto writer = std::make_unique<telemetry::LogWriter>(
        path,
        telemetry::LogHeader{cfg.loop.sample_period_s(), realtime ? unix_now_ns() : 0,
                             realtime ? 0u : 1u, cfg.effective_yaml},
        ring, 512, std::chrono::milliseconds(5),
        realtime ? telemetry::LogWriter::Flush::kEveryPoll
                 : telemetry::LogWriter::Flush::kFullBlocks);
    writer->start();
    return writer;
  } catch (const std::exception& e) {
    throw config::ConfigError({e.what()});
  }
}

}  // namespace

int run_command(const RunOptions& options) {
  block_run_signals();  // before any thread exists; see run_threads.h
  const config::Config cfg = load_config(options.config);
  const bool realtime = cfg.loop.clock == config::ClockMode::kRealtime;

  std::unique_ptr<Device> device = make_device(cfg);
  device->configure();
  const gate::GateReport report = gate::evaluate_gate(cfg, device->transport_delay_samples());
  if (!announce_gate(report, cfg)) return kExitGateRefused;

  const int cpus = static_cast<int>(std::thread::hardware_concurrency());
  if (realtime && cfg.loop.cpu >= cpus) {
    throw config::ConfigError({cfg.source_name + ": loop.cpu: CPU " + std::to_string(cfg.loop.cpu) +
                               " does not exist (this machine has " + std::to_string(cpus) + ")"});
  }
  loop::RtStatus rt;
  std::optional<loop::CpuDmaLatencyRequest> pm_qos;
  if (realtime) {
    lock_process_memory(rt);
    pm_qos.emplace(rt);
    keep_off_cpu(cfg.loop.cpu, rt);  // before any other thread exists, so they inherit it
  }

  // Tick log: the ring is sized and touched now, never on the RT thread.
  const std::string log_path = options.log_path.empty() ? cfg.telemetry.log_path : options.log_path;
  std::unique_ptr<SpscRing<TickRecord>> ring;
  std::unique_ptr<telemetry::LogWriter> writer;
  if (!log_path.empty()) {
    ring = std::make_unique<SpscRing<TickRecord>>(cfg.telemetry.ring_capacity);
    writer = open_log(log_path, cfg, realtime, *ring);
  }

  control::Controller controller(control::make_control_law(cfg));
  loop::LoopOptions lo;
  lo.realtime = realtime;
  lo.period_ns = std::llround(1e9 / cfg.loop.rate_hz);
  lo.overrun_fault_streak = cfg.loop.overrun_fault_streak;
  lo.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  lo.max_speed = cfg.safety.max_speed;
  lo.wait_for_ring = !realtime && writer != nullptr;  // a simulation logs every tick
  if (options.duration_s) {
    lo.max_ticks = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(*options.duration_s * cfg.loop.rate_hz)));
  }
  loop::ServoLoop servo(*device, controller, ring.get(), lo);

  device->enable_output();
  std::string stop_reason;
  loop::LoopResult result;
  {
    const OutputGuard output_off(*device);  // on every path out of here, exceptions included
    RtThread rt_thread(servo, cfg.loop.rt_priority, cfg.loop.cpu, realtime, rt);
    if (const std::string error = rt_thread.wait_ready(); !error.empty()) {
      throw config::ConfigError({cfg.source_name + ": " + error});
    }
    spdlog::info("output enabled: {} at {} Hz ({}), wall K {} N/m B {} N s/m", device->name(),
                 cfg.loop.rate_hz, realtime ? "realtime" : "freerun", cfg.wall.stiffness,
                 cfg.wall.damping);
    if (realtime) announce_rt(rt);
    sd_notifyf(0, "READY=1\nSTATUS=servo running at %.0f Hz", cfg.loop.rate_hz);
    stop_reason = rt_thread.supervise();
    result = rt_thread.result();
  }
  sd_notify(0, "STOPPING=1\nSTATUS=output disabled");
  if (writer) writer->stop();

  RunSummary s;
  s.realtime = realtime;
  s.sample_period_s = cfg.loop.sample_period_s();
  s.loop = result;
  s.wake_latency = &servo.wake_latency();
  s.compute_time = &servo.compute_time();
  s.rt = rt;
  s.stop_reason = result.fault.cause != loop::FaultCause::kNone ? "fault" : stop_reason;
  if (result.fault.cause != loop::FaultCause::kNone) {
    std::string f = loop::describe(result.fault);
    if (result.fault.cause == loop::FaultCause::kDeviceRead ||
        result.fault.cause == loop::FaultCause::kDeviceWrite) {
      f += ": " + device->describe_error();
    }
    spdlog::error("fault: {}; zero force commanded, output disabled", f);
    s.faults.push_back(f);
  }
  if (result.unarmed_ticks > 0) {
    spdlog::warn(
        "the device started inside the wall: the wall stayed off for {} ticks until it "
        "was first left",
        result.unarmed_ticks);
  }
  if (const auto* simdev = dynamic_cast<const sim::SimDevice*>(device.get())) {
    s.operator_work_j = simdev->plant().operator_work_j();
  }
  if (writer) {
    s.log_path = writer->path();
    s.log_records_written = writer->records_written();
    s.log_records_dropped = writer->records_dropped();
    s.log_io_errors = writer->io_errors();
    if (s.log_records_dropped > 0) {
      spdlog::warn("tick log: the ring dropped {} records (marked in the log)",
                   s.log_records_dropped);
    }
    if (s.log_io_errors > 0) {
      // The servo kept running, but the record of the run is incomplete: that is a failure.
      s.faults.push_back("tick log: " + std::to_string(s.log_io_errors) +
                         " write errors, first: " + writer->last_error());
      spdlog::error("{}", s.faults.back());
    }
  }
  s.gate = gate::gate_to_json(report);
  std::cout << summary_to_text(s);
  if (!options.summary_json_path.empty()) {
    std::ofstream out(options.summary_json_path);
    out << summary_to_json(s).dump(2) << "\n";
    if (!out) {
      spdlog::error("{}: cannot write the summary", options.summary_json_path);
      return kExitRuntimeFault;
    }
  }
  return s.faults.empty() ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
