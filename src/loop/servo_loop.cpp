// The tick, and everything it touches. The RT working set is kept small and listed here, so a
// change that adds to it is seen: the Device (its state, the driver's buffers), the
// Controller (ControlLaw and three 16-tap histories, the delay line), the PassivityObserver
// (two command histories as long as the device's delay, allocated before the loop), the
// DirectionProbe until the wall is armed (its rest ring and fit window, allocated before the
// loop), this ServoLoop (options, two 4 KB LatencyHistograms, its counters, the LiveStatus
// atomics), the LawSwap and WallMoves mailboxes (one atomic load a tick each), the Schedule,
// SampleCheck and TickRecord on the stack, one slot of the SPSC ring and one of the clients'
// state block (a shared mapping, prefaulted). Nothing else: no
// allocation, no lock, no log, no throw.
#include "loop/servo_loop.h"

#include <sched.h>

#include <algorithm>
#include <cmath>

#include "base/clock.h"
#include "loop/rt_setup.h"
#include "loop/tick.h"

namespace hapticd::loop {
namespace {

using base::kNsPerS;

// A joint's checks for several joints' read, kept out of line: the one-joint tick's own call is
// then the only other, and the compiler inlines the checks there as it did before joints.
[[gnu::noinline]] Sensed check_joint(SampleCheck& check, std::uint64_t tick, std::int64_t wake,
                                     IoStatus status, PositionSample& sample,
                                     telemetry::TickRecord& rec) noexcept {
  return check.check(tick, wake, status, sample, rec);
}

control::ObserverParams with_period(control::ObserverParams p, std::int64_t period_ns) {
  p.sample_period = static_cast<double>(period_ns) / kNsPerS;
  return p;
}

}  // namespace

ServoLoop::ServoLoop(Device& device, control::Controller& controller,
                     telemetry::SpscRing<telemetry::TickRecord>* ring, const LoopOptions& options)
    : device_(device),
      controller_(&controller),
      ring_(ring),
      options_(options),
      observer_(with_period(options.observer, options.sample.period_ns)),
      probe_(options.probe),
      publisher_(options.state, options.sample.period_ns) {}

void ServoLoop::set_fault(Fault f, telemetry::TickRecord& rec, LoopResult& res) const noexcept {
  res.fault = f;
  rec.flags |= telemetry::kFlagFault;
  rec.fault_cause = static_cast<std::uint8_t>(f.cause);
  if (f.cause == FaultCause::kTransportRead || f.cause == FaultCause::kTransportWrite ||
      f.cause == FaultCause::kDeviceReported) {
    const DeviceFault df = device_.fault();
    rec.fault_class = static_cast<std::uint8_t>(df.fault_class);
    rec.fault_code = df.code;
  }
}

void ServoLoop::check_write(IoStatus written, std::uint64_t tick, telemetry::TickRecord& rec,
                            LoopResult& res) const noexcept {
  if (written != IoStatus::kTransportFault && written != IoStatus::kDeviceFault) return;
  set_fault({written == IoStatus::kDeviceFault ? FaultCause::kDeviceReported
                                               : FaultCause::kTransportWrite,
             tick, 0.0},
            rec, res);
}

void ServoLoop::log(const telemetry::TickRecord& rec, const std::atomic<bool>& stop) noexcept {
  if (ring_ == nullptr) return;
  while (options_.wait_for_ring && ring_->size_approx() >= ring_->capacity() &&
         !stop.load(std::memory_order_relaxed)) {
    sched_yield();
  }
  ring_->try_push(rec);  // realtime: a full ring counts the loss, never blocks
}

void ServoLoop::account(const telemetry::TickRecord& rec, const Sensed& sensed,
                        LoopResult& res) noexcept {
  if (sensed.stale) counters_[kCounterStaleTicks].add();
  if (sensed.gap > 0) {
    counters_[kCounterSequenceGaps].add();
    counters_[kCounterSamplesMissed].add(sensed.gap);
  }
  if (rec.flags & telemetry::kFlagOverrun) counters_[kCounterOverruns].add();
  if (rec.flags & telemetry::kFlagContact) counters_[kCounterContactTicks].add();
  if (rec.flags & telemetry::kFlagSaturated) counters_[kCounterSaturatedTicks].add();
  if (rec.flags & telemetry::kFlagUnarmed) counters_[kCounterUnarmedTicks].add();
  res.max_penetration = std::max(res.max_penetration, rec.penetration);
  constexpr auto r = std::memory_order_relaxed;
  live_.position.store(rec.position, r);
  live_.penetration.store(rec.penetration, r);
  live_.force_commanded.store(rec.force_commanded, r);
  if (options_.scene != nullptr) {
    account_joints(rec);
    return;
  }
  live_.wall_energy_j.store(observer_.wall_work_j(), r);
  live_.observer_energy_j.store(observer_.energy_j(), r);
  live_.damped_ticks.store(observer_.damped_ticks(), r);
}

void ServoLoop::account_joints(const telemetry::TickRecord& rec) noexcept {
  constexpr auto r = std::memory_order_relaxed;
  const double q[] = {rec.position, rec.joint_position[0], rec.joint_position[1]};
  const double tau[] = {rec.force_commanded, rec.joint_force[0], rec.joint_force[1]};
  for (std::size_t j = 0; j < base::kMaxJoints; ++j) {
    live_.joint_position[j].store(q[j], r);
    live_.joint_force[j].store(tau[j], r);
    live_.task_position[j].store(rec.task_position[j], r);
  }
  // The walls' observers' energy is the record's (their sum); a tick any of them damped counts.
  if (rec.flags & telemetry::kFlagPassivityDamped) ++scene_damped_ticks_;
  live_.wall_energy_j.store(wall_work_j(), r);
  if (rec.flags & telemetry::kFlagStepped) live_.observer_energy_j.store(rec.observer_energy_j, r);
  live_.damped_ticks.store(scene_damped_ticks_, r);
}

double ServoLoop::wall_work_j() const noexcept {
  if (options_.scene == nullptr) return observer_.wall_work_j();
  const SceneWalls& walls = *options_.scene->walls;
  double work = walls.ended.wall_work_j;
  for (const control::PassivityObserver& o : walls.observers) work += o.wall_work_j();
  return work;
}

void ServoLoop::run_counts(const std::array<std::uint64_t, kLoopCounterCount>& before,
                           LoopResult& res) const noexcept {
  for (std::size_t c = 0; c < kLoopCounterCount; ++c)
    res.counts[c] = counters_[c].value() - before[c];
}

PassivityResult ServoLoop::passivity() const noexcept {
  if (options_.scene != nullptr) return scene_passivity();
  PassivityResult p;
  p.observed = observer_.enabled();
  p.energy_j = observer_.energy_j();
  p.min_energy_j = observer_.min_energy_j();
  p.negative_ticks = observer_.negative_ticks();
  p.damped_ticks = observer_.damped_ticks();
  p.max_damping = observer_.max_alpha();
  p.damping_work_j = observer_.damping_work_j();
  return p;
}

void ServoLoop::write_zero() noexcept {
  const std::array<double, base::kMaxJoints> zero{};
  device_.write(std::span<const double>(zero.data(), device_.info().joints));
}

Sensed ServoLoop::read_joint(std::uint64_t tick, std::int64_t wake, std::uint32_t periods,
                             SampleCheck& check, telemetry::TickRecord& rec) noexcept {
  PositionSample sample;
  const IoStatus rs = device_.read(std::span<PositionSample>(&sample, 1), periods);
  return check.check(tick, wake, rs, sample, rec);
}

Sensed ServoLoop::read_joints(std::uint64_t tick, std::int64_t wake, std::uint32_t periods,
                              std::span<SampleCheck> checks, kinematics::Vec3& q,
                              telemetry::TickRecord& rec) noexcept {
  std::array<PositionSample, base::kMaxJoints> samples{};
  const std::size_t n = device_.info().joints;
  const IoStatus rs = device_.read(std::span<PositionSample>(samples.data(), n), periods);
  Sensed all = check_joint(checks[0], tick, wake, rs, samples[0], rec);
  q[0] = all.position;
  for (std::size_t i = 1; i < n; ++i) {
    telemetry::TickRecord joint;  // the first joint's sample fields are the record's
    const Sensed s = check_joint(checks[i], tick, wake, rs, samples[i], joint);
    rec.flags |= joint.flags;
    q[static_cast<int>(i)] = s.position;
    all.has_position = all.has_position && s.has_position;
    all.fresh = all.fresh && s.fresh;
    all.stale = all.stale || s.stale;
    all.gap = std::max(all.gap, s.gap);
    if (all.fault.cause == FaultCause::kNone) all.fault = s.fault;
  }
  rec.joints = static_cast<std::uint8_t>(n);
  return all;
}

void ServoLoop::scene_tick(std::uint64_t tick, std::int64_t wake, const Sensed& sensed,
                           const kinematics::Vec3& q, std::uint32_t periods,
                           telemetry::TickRecord& rec, LoopResult& res) noexcept {
  SceneState& st = *options_.scene;
  ClientForce* client = options_.client_force;
  const kinematics::Vec3 commanded = client ? client->step(wake) : kinematics::Vec3::Zero();
  if (client != nullptr && client->limited()) rec.flags |= telemetry::kFlagClientForceLimited;
  JointCommand c;
  if (sensed.has_position) {
    c = step_scene_tick(st, {q, sensed.fresh, periods, commanded}, rec);
    if (c.non_finite) set_fault({FaultCause::kNonFiniteForce, tick, rec.force_computed}, rec, res);
    if (c.runaway) {
      // What the walls can hold: the penetration at which they ask kRunawayMargin times what
      // the saturated joints render, or the explicit bound.
      const double bound = st.walls->scene->wall_law(rec.deepest_wall).runaway_penetration;
      set_fault({FaultCause::kRunaway, tick, rec.penetration,
                 std::isfinite(bound) ? bound : config::kRunawayMargin * c.scale * rec.penetration},
                rec, res);
    }
    if (c.pose_fault) set_fault({FaultCause::kPose, tick, double(rec.pose_status)}, rec, res);
  }
  if (res.fault.cause == FaultCause::kNone) {
    check_write(device_.write(std::span<const double>(c.tau.data(), device_.info().joints)), tick,
                rec, res);
  }
  const bool faulted = res.fault.cause != FaultCause::kNone;
  if (faulted) write_zero();  // zero on every joint at once; the service disables output
  end_scene_tick(st, faulted ? nullptr : &c, rec);
  task_force_ = faulted ? kinematics::Vec3::Zero() : c.force;
  // What of the client's force acted: its share of what the saturation let through.
  const bool acted = !faulted && sensed.has_position;
  if (client != nullptr) {
    client->acted(acted ? kinematics::Vec3(c.scale * commanded) : kinematics::Vec3::Zero(),
                  st.guess, st.guess.allFinite());
  }
}

PassivityResult ServoLoop::scene_passivity() const noexcept {
  // The walls' observers together (SceneWalls::totals), the ticks any of them damped.
  const SceneWalls::Totals t = options_.scene->walls->totals();
  PassivityResult p;
  p.observed = observer_.enabled();
  p.damped_ticks = scene_damped_ticks_;
  p.energy_j = t.energy_j;
  p.min_energy_j = t.min_energy_j;
  p.negative_ticks = t.negative_ticks;
  p.max_damping = t.max_damping;
  p.damping_work_j = t.damping_work_j;
  return p;
}

// The checks inlined here, as before joints (BENCHMARKS.md): one call a tick saved is 40
// instructions.
[[gnu::flatten]] Sensed ServoLoop::device_tick(std::uint64_t tick, std::int64_t wake,
                                               std::uint32_t periods, std::span<SampleCheck> checks,
                                               telemetry::TickRecord& rec,
                                               LoopResult& res) noexcept {
  kinematics::Vec3 q;  // several joints: what the scene acts on (read_joints fills it)
  const Sensed sensed = options_.scene != nullptr ? read_joints(tick, wake, periods, checks, q, rec)
                                                  : read_joint(tick, wake, periods, checks[0], rec);
  if (sensed.fault.cause != FaultCause::kNone) set_fault(sensed.fault, rec, res);
  if (!sensed.has_position && res.fault.cause == FaultCause::kNone) {
    rec.flags |= telemetry::kFlagNoPosition;
  }
  if (options_.scene != nullptr) {
    scene_tick(tick, wake, sensed, q, periods, rec, res);
    return sensed;
  }
  ClientForce* client = options_.client_force;
  const double commanded = client ? client->step(wake)[0] : 0.0;
  if (client != nullptr && client->limited()) rec.flags |= telemetry::kFlagClientForceLimited;
  TickCommand c;
  if (sensed.has_position && !probe_.ended()) {  // a client's force waits for the check
    c.command = probe_tick(tick, sensed.position, periods, rec, res);
  } else if (sensed.has_position) {
    c = step_tick(*controller_, observer_, TickInput::checked(sensed, periods, commanded), rec);
    if (c.non_finite) set_fault({FaultCause::kNonFiniteForce, tick, rec.force_computed}, rec, res);
    if (c.runaway) {
      set_fault(
          {FaultCause::kRunaway, tick, rec.penetration, controller_->law().runaway_penetration},
          rec, res);
    }
  }
  if (res.fault.cause == FaultCause::kNone) check_write(device_.write(c.command), tick, rec, res);
  if (res.fault.cause != FaultCause::kNone) {
    c = {};
    device_.write(0.0);  // zero force at once; the service then disables output
  }
  end_tick(observer_, c, rec);
  if (client != nullptr) {  // what of the client's force acted, and where
    client->acted(kinematics::Vec3(c.client, 0.0, 0.0), kinematics::Vec3(rec.position, 0.0, 0.0),
                  sensed.has_position);
  }
  return sensed;
}

double ServoLoop::probe_tick(std::uint64_t tick, double position, std::uint32_t periods,
                             telemetry::TickRecord& rec, LoopResult& res) noexcept {
  rec.flags |= telemetry::kFlagProbe;
  rec.position = position;
  const double force = probe_.step(position, periods);
  const control::ProbeResult& r = probe_.result();
  constexpr auto rel = std::memory_order_relaxed;
  live_.direction_gain.store(r.gain, rel);
  live_.direction.store(r.state, rel);
  if (!probe_.ended()) return force;
  const bool no_motion = r.state == control::ProbeState::kNoMotion;
  if (r.state == control::ProbeState::kReversed) {
    set_fault({FaultCause::kForceReversed, tick, r.gain, r.gain_error}, rec, res);
  } else if ((no_motion || r.state == control::ProbeState::kNeverAtRest) &&
             options_.refuse_no_motion) {
    set_fault({no_motion ? FaultCause::kNoProbeMotion : FaultCause::kNeverAtRest, tick, r.gain,
               r.gain_error},
              rec, res);
  } else {
    live_.armed.store(true, std::memory_order_release);
  }
  return force;
}

LoopResult ServoLoop::run(const std::atomic<bool>& stop) noexcept {
  prefault_stack();
  LoopResult res;
  std::array<std::uint64_t, kLoopCounterCount> before{};
  for (std::size_t i = 0; i < before.size(); ++i) before[i] = counters_[i].value();
  Schedule schedule(options_.sample.realtime, options_.sample.period_ns,
                    options_.overrun_fault_streak);
  std::array<SampleCheck, base::kMaxJoints> checks{
      SampleCheck(options_.sample), SampleCheck(options_.sample), SampleCheck(options_.sample)};
  observer_.restart();  // nothing in flight from an earlier run
  probe_.restart();     // every arming checks the direction again
  if (options_.scene != nullptr) options_.scene->restart();
  if (options_.client_force != nullptr) options_.client_force->restart();
  publisher_.restart();
  live_.direction.store(probe_.result().state, std::memory_order_relaxed);
  live_.direction_gain.store(0.0, std::memory_order_relaxed);
  live_.armed.store(probe_.ended(), std::memory_order_release);
  const double work_before = wall_work_j();
  if (next_tick_ > 0) mark_rearmed(stop);  // enabled again after a fault

  for (std::uint64_t n = 0;; ++n) {
    if (stop.load(std::memory_order_relaxed)) break;
    if (options_.max_ticks != 0 && n >= options_.max_ticks) break;
    const std::uint64_t tick = next_tick_ + n;
    telemetry::TickRecord rec;
    rec.tick = tick;
    const std::int64_t wake = schedule.wait(tick, rec);
    take_reloads(tick, rec.scheduled_ns, stop);
    take_moves(tick, rec.scheduled_ns, stop);
    const Sensed sensed = device_tick(tick, wake, schedule.periods(), checks, rec, res);
    std::int64_t compute_ns = 0;
    const Fault late = schedule.judge(tick, wake, rec, compute_ns);
    compute_time_.record(compute_ns);
    if (options_.sample.realtime) wake_latency_.record(schedule.latency());
    if (late.cause != FaultCause::kNone && res.fault.cause == FaultCause::kNone) {
      set_fault(late, rec, res);
      write_zero();
      rec.force_commanded = 0.0;
      rec.joint_force[0] = rec.joint_force[1] = 0.0;
    }
    account(rec, sensed, res);
    log(rec, stop);
    publisher_.publish(rec, schedule.periods(), wake,
                       options_.scene != nullptr && res.fault.cause == FaultCause::kNone
                           ? task_force_
                           : kinematics::Vec3(rec.force_commanded, 0.0, 0.0));
    ++res.ticks;
    ticks_done_.store(next_tick_ + res.ticks, std::memory_order_relaxed);
    if (res.fault.cause != FaultCause::kNone) break;
    const std::int64_t skipped = schedule.advance();
    counters_[kCounterMissedTicks].add(static_cast<std::uint64_t>(skipped));
    for (SampleCheck& c : checks) c.skipped(skipped);
  }
  write_zero();  // the last command must not outlive the loop that was servoing it
  if (options_.law_swap != nullptr) options_.law_swap->loop_ended();  // no more takes
  if (options_.scene_swap != nullptr) options_.scene_swap->loop_ended();
  if (options_.wall_moves != nullptr) options_.wall_moves->loop_ended();
  next_tick_ += res.ticks;
  run_counts(before, res);
  res.wall_energy_j = wall_work_j() - work_before;
  res.passivity = passivity();
  res.direction = probe_.result();
  return res;
}

}  // namespace hapticd::loop
