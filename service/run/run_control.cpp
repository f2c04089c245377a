// RunSession's answers to the control socket: status, stop, clear-fault, and the held state a
// fault leaves the run in with `--on-fault hold` (a reload and a scene request:
// run_reload.cpp).
#include <poll.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <span>
#include <thread>

#include "gate/number_format.h"
#include "kinematics/kinematics.h"
#include "service/exit_codes.h"
#include "service/run/counters_report.h"
#include "service/run/gate_derate.h"
#include "service/run/rearm_position.h"
#include "service/run/run_session.h"

namespace hapticd::service {
namespace {

using nlohmann::json;

json percentiles_us(const loop::LatencyHistogram& h) {
  if (h.count() == 0) return nullptr;
  const auto us = [&](double q) { return static_cast<double>(h.percentile_ns(q)) / 1e3; };
  return {{"p50", us(0.5)}, {"p99", us(0.99)}, {"p999", us(0.999)}, {"max", us(1.0)}};
}

}  // namespace

json RunSession::handle(const Request& request) {
  switch (request.command) {
    case Command::kStatus:
      return {{"status", status()}};
    case Command::kStop: {
      {
        std::lock_guard lock(mutex_);
        stop_asked_ = true;
      }
      const std::uint64_t one = 1;
      [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);
      spdlog::info("control socket: stop requested");
      return {{"stopping", true}};
    }
    case Command::kReload:
      return reload(request.config_text, request.source, {});
    case Command::kClearFault:
      return clear_fault();
    case Command::kScene:
      return scene(request.scene, request.client);
    case Command::kServoCf:
      return servo_cf(request);
    case Command::kStream:
      return {{"stream", stream_->subscribe(request.client, request.every)}};
    case Command::kState: {
      // The block is made with the socket, before any request can arrive (run()).
      std::lock_guard lock(mutex_);
      return {{"state",
               {{"layout", client::kStateLayout},
                {"header_bytes", client::kStateHeaderBytes},
                {"slot_bytes", client::kStateSlotBytes},
                {"slots", state_->slots()},
                {"sample_period_ns", cfg_.loop.period_ns()},
                {"joints", kinematics::joint_count(cfg_.device.kinematics)},
                {"axes", kinematics::joint_count(cfg_.device.kinematics)}}}};
    }
  }
  throw ControlRefusal("unknown command");
}

bool RunSession::push(std::uint64_t client, std::size_t pending, std::string& out) {
  return stream_ != nullptr && stream_->push(client, pending, out);
}

int RunSession::push_wait_ms() const { return stream_ != nullptr ? stream_->wait_ms() : -1; }

int RunSession::descriptor(const Request& request) {
  return request.command == Command::kState ? state_->fd() : -1;
}

json RunSession::status() const {
  std::lock_guard lock(mutex_);
  json j;
  j["schema_version"] = kSummarySchemaVersion;
  j["state"] = name(phase_);
  j["driver"] = cfg_.device.driver;
  j["config"] = cfg_.source_name;
  j["rate_hz"] = cfg_.loop.rate_hz;
  j["clock"] = realtime_ ? "realtime" : "freerun";
  const Device& d = session_->device();
  j["device"] = {
      {"state", std::string(to_string(d.state()))},
      {"description",
       d.state() == DeviceState::kUnconfigured ? json(nullptr) : json(d.info().description)},
      {"output_enabled", d.output_enabled()},
      {"last_command", d.last_command()}};
  const std::vector<base::CounterReading> counters = read_run_counters(servo_.get(), d);
  j["counters"] = counters_json(counters);
  j["anomalies"] = anomalies_json(counters);
  const int joints = kinematics::joint_count(cfg_.device.kinematics);
  if (joints > 1) {
    json walls = json::array();
    const auto axes = [joints](const kinematics::Vec3& v) {
      json a = json::array();
      for (int i = 0; i < joints; ++i) a.push_back(v[i]);
      return a;
    };
    for (const config::TaskWallConfig& w : cfg_.walls) {
      const bool attractor = w.kind == config::WallKind::kAttractor;
      walls.push_back({{"kind", attractor ? "attractor" : "wall"},  // schema 7
                       {"stiffness", w.law.stiffness},
                       {"damping", w.law.damping},
                       {"point", axes(w.point)},
                       {"normal", attractor ? json(nullptr) : axes(w.normal)},
                       {"max_force", attractor && std::isfinite(w.max_force) ? json(w.max_force)
                                                                             : json(nullptr)}});
    }
    j["wall"] = nullptr;
    j["walls"] = walls;
  } else {
    j["wall"] = {{"stiffness", cfg_.wall.stiffness}, {"damping", cfg_.wall.damping}};
    j["walls"] = nullptr;
  }
  derated_to_json(derated_, j);
  j["fault"] = fault_.empty() ? json(nullptr) : json(fault_);
  j["gate"] = gate_;
  if (servo_) {
    const loop::LiveStatus& live = servo_->live();
    constexpr auto r = std::memory_order_relaxed;
    j["tick"] = servo_->ticks_done();
    j["reloads"] = reloads_;
    j["position"] = live.position.load(r);
    if (joints > 1) {  // schema 4: every joint and the pose
      json each = json::array();
      for (int i = 0; i < joints; ++i) {
        each.push_back(
            {{"position", live.joint_position[static_cast<std::size_t>(i)].load(r)},
             {"force_commanded", live.joint_force[static_cast<std::size_t>(i)].load(r)}});
      }
      j["joints"] = each;
      j["task_position"] = {live.task_position[0].load(r), live.task_position[1].load(r),
                            live.task_position[2].load(r)};
    } else {
      j["joints"] = nullptr;
      j["task_position"] = nullptr;
    }
    j["penetration"] = live.penetration.load(r);
    j["force_commanded"] = live.force_commanded.load(r);
    j["wall_energy_j"] = live.wall_energy_j.load(r);
    j["observer_energy_j"] = live.observer_energy_j.load(r);
    j["passivity_damped_ticks"] = live.damped_ticks.load(r);
    j["direction_check"] = {{"state", control::probe_state_name(live.direction.load(r))},
                            {"gain", live.direction_gain.load(r)},
                            {"armed", live.armed.load(r)}};
    j["wake_latency_us"] = realtime_ ? percentiles_us(servo_->wake_latency()) : json(nullptr);
    j["compute_us"] = percentiles_us(servo_->compute_time());
  }
  return j;
}

json RunSession::clear_fault() {
  std::unique_lock lock(mutex_);
  if (phase_ != Phase::kHeld) {
    throw ControlRefusal(std::string("no fault to clear: the run is ") + name(phase_));
  }
  clear_asked_ = true;
  clear_result_.reset();
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);
  if (!cleared_.wait_for(lock, std::chrono::seconds(10),
                         [&] { return clear_result_.has_value(); })) {
    throw ControlRefusal("clear-fault: no answer from the supervisor within 10 s");
  }
  if (!clear_result_->empty()) throw ControlRefusal("clear-fault refused: " + *clear_result_);
  return {{"cleared", true}};
}

// A fault is latched (output off); wait for clear-fault (true: re-arm) or a stop (false).
bool RunSession::hold() {
  set_phase(Phase::kHeld);
  spdlog::error("fault latched, output disabled: waiting for `hapticctl clear-fault` or a stop");
  // Up, though never armed when the fault came during the direction check: systemd's start is
  // over either way (a second READY=1 is ignored).
  sd_notify(0, "READY=1\nSTATUS=faulted: output disabled, waiting for clear-fault");
  pollfd fds[3] = {
      {signals_.fd(), POLLIN, 0}, {signals_.pipe_fd(), POLLIN, 0}, {wake_fd_, POLLIN, 0}};
  for (;;) {
    poll(fds, 3, 500);
    sd_notify(0, "WATCHDOG=1");  // alive and safe: the loop is meant not to run
    if (const auto sig = signals_.take_pending()) on_signal(*sig, nullptr);
    std::uint64_t drained = 0;
    while (read(wake_fd_, &drained, sizeof drained) > 0) {
    }
    std::unique_lock lock(mutex_);
    if (stop_asked_) {
      if (summary_.stop_reason == "duration") summary_.stop_reason = "control socket: stop";
      return false;
    }
    if (!clear_asked_) continue;
    clear_asked_ = false;
    lock.unlock();
    const std::string why = try_clear();
    lock.lock();
    clear_result_ = why;
    cleared_.notify_all();
    if (why.empty()) {
      fault_.clear();
      // Cleared: history, not a failure of the run (the summary lists it apart).
      summary_.cleared_faults.insert(summary_.cleared_faults.end(), summary_.faults.begin(),
                                     summary_.faults.end());
      summary_.faults.clear();
      spdlog::info("fault cleared: re-arming through the gate");
      return true;
    }
    spdlog::warn("clear-fault refused: {}", why);
  }
}

// Re-arms only through the same gate and only with the device outside the wall; "" when it
// may, else why not.
std::string RunSession::try_clear() {
  config::Config cfg;
  {
    std::lock_guard lock(mutex_);
    cfg = cfg_;
  }
  Device& device = session_->device();
  const gate::GateReport report = gate::evaluate_gate(cfg, device.info().transport_delay_samples);
  if (!gate_allows(report, cfg)) {
    return "the gate refuses the configuration: " + joined(report.reasons);
  }
  try {
    if (device.state() == DeviceState::kFaulted) device.clear_fault();
  } catch (const DeviceError& e) {
    return e.what();
  }
  std::array<PositionSample, base::kMaxJoints> s{};
  const std::span<PositionSample> samples(s.data(), device.info().joints);
  for (int attempt = 0; attempt < 100; ++attempt) {
    const IoStatus st = device.read(samples);
    if (st == IoStatus::kTransportFault || st == IoStatus::kDeviceFault) {
      return "the device faults again: " + device.describe_fault();
    }
    if (st == IoStatus::kOk) return rearm_refusal(cfg, samples);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return "no position from the device to check it is outside the wall";
}

}  // namespace hapticd::service
