#include "service/run/run_session.h"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>
#include <csignal>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <optional>
#include <system_error>
#include <thread>

#include "config/config_loader.h"
#include "kinematics/kinematics.h"
#include "service/exit_codes.h"
#include "service/run/counters_report.h"
#include "service/run/crash_guard.h"
#include "service/run/direction_report.h"

namespace hapticd::service {
namespace {

// The clients' state block holds the last 4096 ticks (4 s at 1 kHz; 768 KiB): a reader that
// wakes every frame of a 60 Hz display, or every 100 ms, misses nothing.
constexpr std::uint32_t kStateSlots = 4096;

void drain(int fd) {
  std::uint64_t n = 0;
  while (read(fd, &n, sizeof n) > 0) {
  }
}

// A loop asked to stop ends at its next tick, writing zero. One still running well after that
// is stuck (its thread blocked or starved of the CPU: what systemd's watchdog catches) and
// writes nothing more, so the device's emergency stop is written from here, once; the loop
// still ends the ordinary way if it ever ticks again (docs/operations.md, the watchdog).
class StuckLoopGuard {
 public:
  explicit StuckLoopGuard(double period_s)
      : limit_(std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(std::max(0.5, 10 * period_s)))) {}
  void check(bool stopping, Device& device) {
    if (!stopping || written_) return;
    const Clock::time_point now = Clock::now();
    if (!stopping_seen_) since_ = now;
    stopping_seen_ = true;
    if (now - since_ < limit_) return;
    device.emergency_stop();
    written_ = true;
    spdlog::error(
        "the servo loop has not ended {} ms after the stop (its thread is stuck): wrote the "
        "device's emergency stop (zero force, output off)",
        std::chrono::duration_cast<std::chrono::milliseconds>(now - since_).count());
    sd_notify(0, "STATUS=servo loop stuck: emergency stop written");
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::duration limit_;
  Clock::time_point since_{};  // when the stop was first seen
  bool stopping_seen_ = false;
  bool written_ = false;
};

}  // namespace

const char* RunSession::name(Phase p) {
  switch (p) {
    case Phase::kStarting:
      return "starting";
    case Phase::kRunning:
      return "running";
    case Phase::kHeld:
      return "faulted";
    case Phase::kEnded:
      return "ended";
  }
  return "unknown";
}

RunSession::RunSession(const RunOptions& options, config::Config cfg, SignalWatch& signals)
    : options_(options),
      signals_(signals),
      realtime_(cfg.loop.clock == config::ClockMode::kRealtime),
      wake_fd_(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)),
      cfg_(std::move(cfg)) {
  if (wake_fd_ < 0) throw std::system_error(errno, std::system_category(), "eventfd");
  summary_.realtime = realtime_;
  summary_.sample_period_s = cfg_.loop.sample_period_s();
  summary_.stop_reason = "duration";
  summary_.device_name = cfg_.device.driver;
  summary_.passivity_mode = control::passivity_mode_name(cfg_.safety.passivity_controller);
}

RunSession::~RunSession() {
  server_.reset();  // its thread calls into this object: gone first
  close(wake_fd_);
}

void RunSession::set_phase(Phase p) {
  std::lock_guard lock(mutex_);
  phase_ = p;
}

// Configures the device and gates it, opens the log, builds the law and the loop.
bool RunSession::start_up(gate::GateReport& report) {
  // On a copy: the control socket may already read cfg_ (and safety.gate: derate changes it).
  config::Config cfg = config_snapshot();
  const bool pass = configure_and_gate(cfg, *session_, summary_, report);
  {
    std::lock_guard lock(mutex_);
    cfg_ = std::move(cfg);
    derated_ = summary_.derated;
    gate_ = summary_.gate;
    report_ = report;
    owners_.assign(cfg_.walls.size(), 0);
  }
  if (!pass) return false;
  const int cpus = static_cast<int>(std::thread::hardware_concurrency());
  if (realtime_ && cfg_.loop.cpu >= cpus) {
    throw config::ConfigError({cfg_.locate("loop.cpu") + ": loop.cpu: CPU " +
                               std::to_string(cfg_.loop.cpu) +
                               " does not exist (this machine has " + std::to_string(cpus) + ")"});
  }
  if (realtime_) {
    lock_process_memory(rt_);
    pm_qos_.emplace(rt_);
    keep_off_cpu(cfg_.loop.cpu, rt_);  // before the RT and log threads exist: they inherit it
  }
  log_ = open_tick_log(options_, cfg_, realtime_);
  active_ = std::make_unique<control::Controller>(control::make_control_law(cfg_));
  loop::LoopOptions lo =
      loop_options(options_, cfg_, session_->device().info(), realtime_, log_.writer != nullptr);
  lo.law_swap = &swap_;
  if (session_->device().info().joints > 1) {
    scene_ = make_scene_parts(cfg_, session_->device().info(), report);
    lo.scene = scene_.state.get();
    lo.scene_swap = &scene_swap_;
    lo.wall_moves = &moves_;
  }
  if (server_) {  // without a control socket no client can command a force: none stepped
    const config::SafetyConfig& s = cfg_.safety;
    client_force_ = std::make_unique<loop::ClientForce>(
        loop::ClientForceLimits{s.client_force_limit, std::llround(s.client_force_hold_ms * 1e6),
                                std::llround(s.client_force_ramp_ms * 1e6), s.client_force_energy_j,
                                cfg_.loop.sample_period_s()});
    lo.client_force = client_force_.get();
  }
  lo.state = state_.get();
  auto servo = std::make_unique<loop::ServoLoop>(session_->device(), *active_, log_.ring.get(), lo);
  summary_.wake_latency = &servo->wake_latency();
  summary_.compute_time = &servo->compute_time();
  if (log_.writer) {
    // The log ends with the run's counters (its counters block), as the summary shows them.
    log_.writer->set_counters(
        [this] { return read_run_counters(servo_.get(), session_->device()); });
  }
  std::lock_guard lock(mutex_);
  servo_ = std::move(servo);
  return true;
}

int RunSession::run() {
  session_.emplace(cfg_, options_.loopback, realtime_);
  check_clock(cfg_, session_->peer() != nullptr);
  if (!options_.socket_path.empty()) {
    // Each task axis is a joint's (kinematics.h): the device is not configured yet to ask it.
    const auto axes = static_cast<std::uint32_t>(kinematics::joint_count(cfg_.device.kinematics));
    state_ =
        std::make_unique<telemetry::StateBlock>(kStateSlots, cfg_.loop.period_ns(), axes, axes);
    stream_ = std::make_unique<StateStream>(state_->fd());
    try {
      server_ = std::make_unique<ControlServer>(options_.socket_path, *this);
    } catch (const std::runtime_error& e) {
      throw config::ConfigError({std::string("--socket ") + e.what()});
    }
  }
  if (stop_requested(signals_, summary_, "during start-up", reload_pending_)) return finish();
  gate::GateReport report;
  if (!start_up(report)) return kExitGateRefused;
  for (;;) {
    accumulate(arm());
    const loop::FaultCause cause = summary_.loop.fault.cause;
    // A device the direction check refused is refused again by every re-arming: never held.
    if (cause == loop::FaultCause::kNone || !options_.on_fault_hold ||
        loop::is_direction_refusal(cause)) {
      break;
    }
    if (!hold()) break;
    // Re-armed: a fresh law from the configuration in force (a reload may have replaced it),
    // recorded after the loop's re-armed marker.
    std::lock_guard lock(mutex_);
    active_ = std::make_unique<control::Controller>(control::make_control_law(cfg_));
    if (pending_walls_) {  // walls reloaded while held: no loop runs, so no swap is needed
      pending_walls_->continue_from(*scene_.walls);
      scene_.state->walls = pending_walls_.get();
      scene_.walls = std::move(pending_walls_);
    }
    if (log_.writer) log_.writer->queue_config_change(cfg_.effective_yaml);
    servo_->set_controller(*active_);
    summary_.loop.fault = {};
  }
  sd_notify(0, "STOPPING=1\nSTATUS=output disabled");
  if (log_.writer) log_.writer->stop();
  summary_.rt = rt_;
  if (loop::is_direction_refusal(summary_.loop.fault.cause)) {
    summary_.stop_reason = "direction check";
  } else if (summary_.loop.fault.cause != loop::FaultCause::kNone) {
    summary_.stop_reason = "fault";
  }
  if (const std::uint64_t unarmed = servo_->counters()[loop::kCounterUnarmedTicks].value()) {
    spdlog::warn(
        "the device started inside the wall: the wall stayed off for {} ticks until it "
        "was first left",
        unarmed);
  }
  summarise_log(log_, summary_);
  return finish();
}

config::Config RunSession::config_snapshot() const {
  std::lock_guard lock(mutex_);
  return cfg_;
}

// Enables output, runs the RT thread until the loop ends, disables output.
loop::LoopResult RunSession::arm() {
  loop::LoopResult result;
  if (stop_requested(signals_, summary_, "before output was enabled", reload_pending_)) {
    return result;
  }
  {
    std::lock_guard lock(mutex_);
    if (stop_asked_) {  // `hapticctl stop` during start-up (or while a fault was held)
      summary_.stop_reason = "control socket: stop";
      spdlog::info("control socket: stop requested before output was enabled");
      return result;
    }
  }
  const config::Config cfg = config_snapshot();  // a reload may replace cfg_ meanwhile
  Device& device = session_->device();
  std::optional<CrashGuard> crash_guard;  // outlives the RT thread and the disable below
  {
    // The RT thread is made, scheduled and pinned before output is enabled, and its loop
    // started right after: a drive's watchdog sees commands within a period of the enable.
    swap_.loop_starting();  // before the phase says running: a reload then waits for this loop
    scene_swap_.loop_starting();
    moves_.loop_starting();
    RtThread rt(*servo_, cfg.loop.rt_priority, cfg.loop.cpu, realtime_, rt_);
    if (const std::string error = rt.wait_ready(); !error.empty()) {
      throw config::ConfigError({cfg.locate("loop.cpu") + ": " + error});
    }
    crash_guard.emplace(device);  // a crash while enabled still writes zero first
    device.enable();
    rt.start();
    rt.wait_running();
    const bool first = !summary_.output_was_enabled;
    summary_.output_was_enabled = true;
    if (device.info().joints > 1) {
      spdlog::info("output enabled: {} at {} Hz ({}), {} walls", device.info().description,
                   cfg.loop.rate_hz, realtime_ ? "realtime" : "freerun", cfg.walls.size());
    } else {
      spdlog::info("output enabled: {} at {} Hz ({}), wall K {} N/m B {} N s/m",
                   device.info().description, cfg.loop.rate_hz, realtime_ ? "realtime" : "freerun",
                   cfg.wall.stiffness, cfg.wall.damping);
    }
    if (realtime_ && first) announce_rt(rt_);
    supervise(rt);  // running (READY=1) once the direction check has armed the wall
    result = rt.join();
  }
  set_phase(Phase::kEnded);
  device.disable();
  summarise_fault(result, device, summary_,
                  direction_advice(result.fault.cause, cfg, session_->driver()));
  if (result.fault.cause != loop::FaultCause::kNone) {
    std::lock_guard lock(mutex_);
    fault_ = summary_.faults.back();
  }
  return result;
}

void RunSession::on_signal(int sig, RtThread* rt) {
  if (sig == SIGHUP) {
    spdlog::info("SIGHUP received: reloading the configuration file");
    reload_file();  // logged either way; the run goes on
    return;
  }
  summary_.stop_reason = "signal " + signal_name(sig);
  spdlog::info("{} received: stopping", signal_name(sig));
  sd_notify(0, "STOPPING=1");
  if (rt != nullptr) rt->request_stop();
  std::lock_guard lock(mutex_);
  stop_asked_ = true;
}

// Until the loop ends: signals, the control socket's stop, the systemd watchdog (fed only
// while ticks advance).
void RunSession::supervise(RtThread& rt) {
  std::uint64_t watchdog_usec = 0;
  const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0;
  std::uint64_t last_ticks = servo_->ticks_done();
  PassivityWatch passivity;
  StuckLoopGuard stuck(summary_.sample_period_s);
  bool running = false;  // the wall armed: phase running, READY=1 sent
  pollfd fds[4] = {{signals_.fd(), POLLIN, 0},
                   {signals_.pipe_fd(), POLLIN, 0},
                   {rt.ended_fd(), POLLIN, 0},
                   {wake_fd_, POLLIN, 0}};
  if (reload_pending_) {  // a SIGHUP taken during start-up
    reload_pending_ = false;
    reload_file();
  }
  while (!rt.finished()) {
    if (!running && servo_->live().armed.load(std::memory_order_acquire)) {
      running = true;
      announce_direction(servo_->direction());
      set_phase(Phase::kRunning);  // before READY=1: whoever waits for it may ask at once
      sd_notifyf(0, "READY=1\nSTATUS=servo running at %.0f Hz", 1.0 / summary_.sample_period_s);
    }
    poll(fds, 4, running ? 50 : 5);  // the time-out paces the watchdog (and READY=1 at first)
    if (const auto sig = signals_.take_pending()) on_signal(*sig, &rt);
    drain(wake_fd_);
    bool stopping = false;
    {
      std::lock_guard lock(mutex_);
      if (stop_asked_ && summary_.stop_reason == "duration") {
        summary_.stop_reason = "control socket: stop";
      }
      if (stop_asked_) rt.request_stop();
      stopping = stop_asked_;
    }
    stuck.check(stopping, session_->device());
    const std::uint64_t ticks = servo_->ticks_done();
    if (watchdog && ticks != last_ticks) sd_notify(0, "WATCHDOG=1");
    last_ticks = ticks;
    watch_passivity(servo_->live(), passivity, 20);  // damping: every 20 polls (about 1 s)
  }
  // A run shorter than a poll (freerun) armed and ended between two looks.
  if (!running && servo_->live().armed.load(std::memory_order_acquire)) {
    announce_direction(servo_->direction());
  }
}

void RunSession::accumulate(const loop::LoopResult& r) {
  // The counts are the loop's counters, read at the end; here what only a run's result holds.
  loop::LoopResult& t = summary_.loop;
  t.ticks += r.ticks;
  t.max_penetration = std::max(t.max_penetration, r.max_penetration);
  t.wall_energy_j += r.wall_energy_j;
  t.passivity = r.passivity;  // already over every run
  t.direction = r.direction;  // the last arming's check
  t.fault = r.fault;
}

int RunSession::finish() {
  server_.reset();  // no request may arrive while the device is closed
  set_phase(Phase::kEnded);
  summarise_device(*session_, servo_.get(), summary_);
  session_->shut_down();
  summarise_peer(*session_, summary_);
  return report(options_, summary_);
}

}  // namespace hapticd::service
