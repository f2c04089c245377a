#include "service/run_command.h"

#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
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
#include "sim/sim_device.h"
#include "telemetry/log_writer.h"

namespace hapticd::service {
namespace {

using telemetry::SpscRing;
using telemetry::TickRecord;

// SIGINT/SIGTERM are blocked in every thread and collected synchronously by the supervisor,
// so no handler runs on the RT thread and nothing async-signal-unsafe happens.
sigset_t stop_signals() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGINT);
  sigaddset(&s, SIGTERM);
  return s;
}

std::int64_t unix_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

struct Supervision {
  std::string stop_reason = "duration";
};

// Waits for the RT thread to finish, turning a stop signal into a stop request and feeding
// the systemd watchdog only while ticks advance.
Supervision supervise(const loop::ServoLoop& loop, std::atomic<bool>& stop,
                      const std::atomic<bool>& finished) {
  Supervision sv;
  const sigset_t sigs = stop_signals();
  std::uint64_t watchdog_usec = 0;
  const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0;
  std::uint64_t last_ticks = 0;
  while (!finished.load()) {
    const timespec wait{0, 50'000'000};
    const int sig = sigtimedwait(&sigs, nullptr, &wait);
    if (sig > 0 && !stop.load()) {
      sv.stop_reason = sig == SIGINT ? "signal SIGINT" : "signal SIGTERM";
      spdlog::info("{} received: stopping", sv.stop_reason.substr(7));
      sd_notify(0, "STOPPING=1");
      stop.store(true);
    }
    const std::uint64_t ticks = loop.ticks_done();
    if (watchdog && ticks != last_ticks) sd_notify(0, "WATCHDOG=1");
    last_ticks = ticks;
  }
  return sv;
}

}  // namespace

int run_command(const RunOptions& options) {
  const config::Config cfg = load_config(options.config);
  const bool realtime = cfg.loop.clock == config::ClockMode::kRealtime;

  std::unique_ptr<Device> device = make_device(cfg);
  device->configure();

  const gate::GateReport report = gate::evaluate_gate(cfg, device->transport_delay_samples());
  if (report.pass) {
    spdlog::info("gate: pass (b_req {:.4g} N s/m <= {:.4g} allowed, delay {} samples)",
                 report.passivity.required_damping, report.passivity.available_damping,
                 report.delay_samples);
  } else {
    for (const std::string& r : report.reasons) spdlog::error("gate: {}", r);
    if (cfg.safety.gate == config::GateMode::kEnforce) {
      std::cerr << gate::gate_to_text(report, cfg);
      return kExitGateRefused;
    }
    spdlog::error(
        "gate: FAILED but safety.gate is 'warn': running a loop that is not proven passive");
  }
  for (const std::string& w : report.warnings) spdlog::warn("gate: {}", w);

  if (realtime && cfg.loop.cpu >= 0 &&
      cfg.loop.cpu >= static_cast<int>(std::thread::hardware_concurrency())) {
    throw config::ConfigError({cfg.source_name + ": loop.cpu: CPU " + std::to_string(cfg.loop.cpu) +
                               " does not exist (this machine has " +
                               std::to_string(std::thread::hardware_concurrency()) + ")"});
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
    try {
      writer = std::make_unique<telemetry::LogWriter>(
          log_path,
          telemetry::LogHeader{cfg.loop.sample_period_s(), realtime ? unix_now_ns() : 0,
                               realtime ? 0u : 1u, cfg.effective_yaml},
          *ring, 512, std::chrono::milliseconds(5),
          realtime ? telemetry::LogWriter::Flush::kEveryPoll
                   : telemetry::LogWriter::Flush::kFullBlocks);
    } catch (const std::runtime_error& e) {
      throw config::ConfigError({e.what()});
    }
    writer->start();
  }

  control::Controller controller(control::make_control_law(cfg));
  loop::LoopOptions lo;
  lo.realtime = realtime;
  lo.period_ns = std::llround(1e9 / cfg.loop.rate_hz);
  lo.overrun_fault_streak = cfg.loop.overrun_fault_streak;
  lo.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  lo.max_speed = cfg.safety.max_speed;
  if (options.duration_s)
    lo.max_ticks = static_cast<std::uint64_t>(std::llround(*options.duration_s * cfg.loop.rate_hz));
  loop::ServoLoop servo(*device, controller, ring.get(), lo);

  const sigset_t sigs = stop_signals();
  pthread_sigmask(SIG_BLOCK, &sigs, nullptr);  // inherited by the RT thread

  device->enable_output();
  spdlog::info("output enabled: {} at {} Hz ({}), wall K {} N/m B {} N s/m", device->name(),
               cfg.loop.rate_hz, realtime ? "realtime" : "freerun", cfg.wall.stiffness,
               cfg.wall.damping);
  sd_notifyf(0, "READY=1\nSTATUS=servo running at %.0f Hz", cfg.loop.rate_hz);

  std::atomic<bool> stop{false};
  std::atomic<bool> rt_ready{false};
  std::atomic<bool> finished{false};
  loop::LoopResult result;
  std::string rt_error;
  std::thread rt_thread([&] {
    try {
      if (realtime) loop::configure_rt_thread(cfg.loop.rt_priority, cfg.loop.cpu, rt);
      rt_ready.store(true, std::memory_order_release);  // publishes `rt` to the supervisor
      result = servo.run(stop);
    } catch (const std::exception& e) {
      rt_error = e.what();  // only configure_rt_thread throws, before the first tick
    }
    finished.store(true);
  });
  // Say which real-time guarantees are in force before the first second of running, not
  // after the run: a service may run for weeks.
  while (!rt_ready.load(std::memory_order_acquire) && !finished.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (realtime && rt_ready.load(std::memory_order_acquire)) {
    spdlog::info("rt: {}{}{}{}{}",
                 rt.fifo ? "SCHED_FIFO " + std::to_string(rt.priority) : "SCHED_OTHER",
                 rt.memory_locked ? ", memory locked" : ", memory not locked",
                 rt.cpu_dma_latency_zero ? ", cpu_dma_latency 0" : "",
                 rt.cpu >= 0 ? ", CPU " + std::to_string(rt.cpu) : "",
                 rt.others_off_rt_cpu ? " (other threads kept off it)" : "");
    for (const std::string& w : rt.warnings) spdlog::warn("rt: {}", w);
  }
  const Supervision sv = supervise(servo, stop, finished);
  rt_thread.join();

  device->disable_output();
  sd_notify(0, "STOPPING=1\nSTATUS=output disabled");
  if (writer) writer->stop();
  if (!rt_error.empty()) throw config::ConfigError({cfg.source_name + ": " + rt_error});

  RunSummary s;
  s.realtime = realtime;
  s.sample_period_s = cfg.loop.sample_period_s();
  s.loop = result;
  s.wake_latency = &servo.wake_latency();
  s.compute_time = &servo.compute_time();
  s.rt = rt;
  s.stop_reason = result.fault.cause != loop::FaultCause::kNone ? "fault" : sv.stop_reason;
  if (result.fault.cause != loop::FaultCause::kNone) {
    std::string f = loop::describe(result.fault);
    if (result.fault.cause == loop::FaultCause::kDeviceRead ||
        result.fault.cause == loop::FaultCause::kDeviceWrite) {
      f += ": " + device->describe_error();
    }
    spdlog::error("fault: {}; zero force commanded, output disabled", f);
    s.faults.push_back(f);
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
    if (s.log_io_errors > 0)
      spdlog::error("tick log: {} write errors: {}", s.log_io_errors, writer->last_error());
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
