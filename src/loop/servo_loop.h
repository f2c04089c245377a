// The fixed-rate servo loop of docs/architecture.md: read the device, step the controller, write
// the force, record the tick. `realtime` sleeps to an absolute CLOCK_MONOTONIC schedule; `freerun`
// never sleeps (sim only: thousands of simulated seconds per second, and byte- identical logs
// because no host timing enters the records).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <span>

#include "base/counters.h"
#include "control/controller.h"
#include "control/direction_probe.h"
#include "control/passivity_observer.h"
#include "drivers/device.h"
#include "loop/client_force.h"
#include "loop/latency_histogram.h"
#include "loop/law_swap.h"
#include "loop/loop_fault.h"
#include "loop/sample_check.h"
#include "loop/scene_tick.h"
#include "loop/schedule.h"
#include "loop/state_publish.h"
#include "loop/wall_moves.h"
#include "telemetry/spsc_ring.h"
#include "telemetry/tick_record.h"

namespace hapticd::loop {

struct LoopOptions {
  // Realtime or freerun, the period, and what each sample is checked against: held once, here
  // (sample_check.h).
  SampleLimits sample;
  int overrun_fault_streak = 10;
  std::uint64_t max_ticks = 0;  // 0: until stop is requested or a fault
  // Freerun only: wait for room in the ring instead of dropping (a simulation is not real
  // time, and a complete log is what makes it reproducible). Needs a consumer.
  bool wait_for_ring = false;
  // Live reload: the mailbox a new control law arrives through (null: none).
  LawSwap* law_swap = nullptr;
  // The runtime passivity observer and controller; its sample_period is the loop's. The
  // default observes with no damping credited (b = 0) and never damps.
  control::ObserverParams observer;
  // The direction check each run() makes before the wall is armed (disabled: armed at once).
  control::ProbePlan probe;
  // What a device that did not move under the check gets: refused (a fault ends the run) or
  // its wall armed unchecked (safety.direction_check.on_no_motion).
  bool refuse_no_motion = true;
  // A device of several joints (docs/kinematics.md, the loop at several joints): its walls,
  // kinematics and observers, stepped in place of the one-joint law, which is then unused, as
  // are `observer`, `probe` and `law_swap` (null: a device of one joint). Owned by the caller.
  SceneState* scene = nullptr;
  // Live reload at several joints: the mailbox new walls arrive through (null: none). Refused
  // reloads are noted on either mailbox.
  SceneSwap* scene_swap = nullptr;
  // A client's wall moves at several joints (null: none): taken at a tick boundary, each
  // marked in the tick log (kMarkerWallMoved).
  WallMoves* wall_moves = nullptr;
  // The clients' state block (null: none): every tick published into it.
  telemetry::StateBlock* state = nullptr;
  // A client's commanded force at several joints (null: none), added to the walls' each tick.
  ClientForce* client_force = nullptr;
};

// What the loop is doing, readable from any thread while it runs (relaxed atomics, stored
// once a tick): for `hapticctl status`. What it counted is in ServoLoop::counters().
struct LiveStatus {
  std::atomic<double> position{0.0};
  std::atomic<double> penetration{0.0};
  std::atomic<double> force_commanded{0.0};
  std::atomic<double> wall_energy_j{0.0};      // LoopResult::wall_energy_j, over every run()
  std::atomic<double> observer_energy_j{0.0};  // PassivityResult::energy_j
  std::atomic<std::uint64_t> damped_ticks{0};  // PassivityResult::damped_ticks
  // The direction check of the current run (control::ProbeState) and its gain so far; the
  // wall is armed once it has ended without refusing the device.
  std::atomic<control::ProbeState> direction{control::ProbeState::kOff};
  std::atomic<double> direction_gain{0.0};
  std::atomic<bool> armed{false};
  // A device of several joints: each joint's position and torque, and the pose (`position`
  // and `force_commanded` are joint 1's); left zero for one joint.
  std::array<std::atomic<double>, base::kMaxJoints> joint_position{};
  std::array<std::atomic<double>, base::kMaxJoints> joint_force{};
  std::array<std::atomic<double>, 3> task_position{};
};

// The loop's counters (ServoLoop::counters()), in this order.
enum LoopCounter : std::size_t {
  kCounterOverruns,
  kCounterMissedTicks,
  kCounterStaleTicks,
  kCounterSequenceGaps,
  kCounterSamplesMissed,
  kCounterContactTicks,
  kCounterSaturatedTicks,
  kCounterUnarmedTicks,
  kCounterReloads,
  kLoopCounterCount
};

// What the passivity observer saw, over every run() of the loop so far.
struct PassivityResult {
  bool observed = false;             // false: safety.passivity_controller off
  double energy_j = 0.0;             // E at the end (J)
  double min_energy_j = 0.0;         // its minimum (J), <= 0
  std::uint64_t negative_ticks = 0;  // ticks that ended with E < 0
  std::uint64_t damped_ticks = 0;    // ticks the controller added damping
  double max_damping = 0.0;          // the most it added (N s/m)
  double damping_work_j = 0.0;       // energy its force took out of the device (J)
};

// What one run() did.
struct LoopResult {
  std::uint64_t ticks = 0;
  // This run's share of each of ServoLoop::counters() (which go on over every run), indexed
  // by LoopCounter: what each count means is said once, in the counter.
  std::array<std::uint64_t, kLoopCounterCount> counts{};
  std::uint64_t count(LoopCounter c) const noexcept { return counts[c]; }
  double max_penetration = 0.0;
  // Work the commanded force did on the device, sum of u (x_k - x_{k-1}) over the ticks with
  // a position, u the force that acted over the period (the ZOH's, written the device's
  // declared delay earlier) (J): negative while the wall takes energy in (pressing into it),
  // positive when it hands energy back; above the energy its spring holds, the wall was active.
  double wall_energy_j = 0.0;
  PassivityResult passivity;
  control::ProbeResult direction;  // the direction check this run made
  Fault fault;
};

class ServoLoop {
 public:
  // Not RT-safe. `ring` may be null (no tick log). `controller` is the law the loop starts
  // with; a live reload (options.law_swap) replaces it at a tick boundary.
  ServoLoop(Device& device, control::Controller& controller,
            telemetry::SpscRing<telemetry::TickRecord>* ring, const LoopOptions& options);

  // Runs on the calling thread (set up as the RT thread) until `stop`, max_ticks or a fault.
  // RT-safe after entry: no allocation, lock, log or throw; blocks only in the device read
  // and the absolute-time sleep. Whatever ends it, it commands zero force before returning.
  // It may run again (after a fault was cleared): ticks go on counting where they stopped (a
  // kMarkerRearmed record marks the first), the timing histograms keep accumulating, and the
  // result is that run's alone.
  LoopResult run(const std::atomic<bool>& stop) noexcept;

  // Not RT-safe; only while run() is not running. The law the next run() starts with.
  void set_controller(control::Controller& controller) noexcept { controller_ = &controller; }

  // Any thread: ticks completed so far, over every run() (for the watchdog and progress), and
  // the rest of what it is doing.
  std::uint64_t ticks_done() const noexcept { return ticks_done_.load(std::memory_order_relaxed); }
  const LiveStatus& live() const noexcept { return live_; }
  // Any thread, once live().armed reads true (acquire) or after run(): what this run's
  // direction check found (it does not change again until the next run()).
  const control::ProbeResult& direction() const noexcept { return probe_.result(); }
  // Off-RT, after run(): the law in force at the end (the last one swapped in).
  control::Controller& controller() const noexcept { return *controller_; }

  // Off-RT, after run(): wake latency and compute time of every tick.
  const LatencyHistogram& wake_latency() const noexcept { return wake_latency_; }
  const LatencyHistogram& compute_time() const noexcept { return compute_time_; }
  // Any thread. What the loop counted over every run() (LoopCounter order): the run's
  // counter registry lists them beside the device's.
  std::span<const base::Counter> counters() const noexcept { return counters_; }

 private:
  // One tick's device work: read, check, step the law, write (zero after a fault). Returns
  // what the checks made of the read. RT-safe: called every tick.
  Sensed device_tick(std::uint64_t tick, std::int64_t wake, std::uint32_t periods,
                     std::span<SampleCheck> checks, telemetry::TickRecord& rec,
                     LoopResult& res) noexcept;
  // device_tick's read for one joint, checked. RT-safe: called every tick.
  Sensed read_joint(std::uint64_t tick, std::int64_t wake, std::uint32_t periods,
                    SampleCheck& check, telemetry::TickRecord& rec) noexcept;
  // device_tick's read for several joints: each joint's sample checked, `q` what the scene
  // acts on; the Sensed of them all (a position only when every joint has one). RT-safe.
  Sensed read_joints(std::uint64_t tick, std::int64_t wake, std::uint32_t periods,
                     std::span<SampleCheck> checks, kinematics::Vec3& q,
                     telemetry::TickRecord& rec) noexcept;
  // device_tick's step and write for several joints. RT-safe: called every tick.
  void scene_tick(std::uint64_t tick, std::int64_t wake, const Sensed& sensed,
                  const kinematics::Vec3& q, std::uint32_t periods, telemetry::TickRecord& rec,
                  LoopResult& res) noexcept;
  // Zero force on every joint. RT-safe.
  void write_zero() noexcept;
  // Records a fault on this tick (the device's class and code for device and transport ones).
  void set_fault(Fault f, telemetry::TickRecord& rec, LoopResult& res) const noexcept;
  // A write the device refused (a transport or device fault) as this tick's fault. RT-safe.
  void check_write(IoStatus written, std::uint64_t tick, telemetry::TickRecord& rec,
                   LoopResult& res) const noexcept;
  // Hands one record to the ring (freerun waits for room). RT-safe: called every tick.
  void log(const telemetry::TickRecord& rec, const std::atomic<bool>& stop) noexcept;
  // Swaps in a law a live reload offered, and marks it (and refusals) in the log.
  // RT-safe: called every tick (one atomic load when nothing is offered).
  void take_reloads(std::uint64_t tick, std::int64_t scheduled_ns,
                    const std::atomic<bool>& stop) noexcept;
  // Moves the walls a client moved, and marks each in the log. RT-safe: called every tick
  // (one atomic load when nothing is offered).
  void take_moves(std::uint64_t tick, std::int64_t scheduled_ns,
                  const std::atomic<bool>& stop) noexcept;
  // Marks where a run after a cleared fault starts its fresh law (kMarkerRearmed). RT-safe.
  void mark_rearmed(const std::atomic<bool>& stop) noexcept;
  // Counts what the tick's record says and stores what `hapticctl status` reads.
  // RT-safe: called every tick.
  void account(const telemetry::TickRecord& rec, const Sensed& sensed, LoopResult& res) noexcept;
  // account's stores for several joints: each joint, the pose, the walls' observers. RT-safe.
  void account_joints(const telemetry::TickRecord& rec) noexcept;
  // This run's share of the counters (LoopResult's counts). RT-safe.
  void run_counts(const std::array<std::uint64_t, kLoopCounterCount>& before,
                  LoopResult& res) const noexcept;
  PassivityResult passivity() const noexcept;
  PassivityResult scene_passivity() const noexcept;
  // The work the commanded force did on the device (the walls' together). RT-safe.
  double wall_work_j() const noexcept;
  // The direction check's tick while it has not ended: its force, its verdict once it has
  // (a refusal is this tick's fault). RT-safe: called every tick until the wall is armed.
  double probe_tick(std::uint64_t tick, double position, std::uint32_t periods,
                    telemetry::TickRecord& rec, LoopResult& res) noexcept;

  Device& device_;
  control::Controller* controller_;
  telemetry::SpscRing<telemetry::TickRecord>* ring_;
  LoopOptions options_;
  control::PassivityObserver observer_;
  control::DirectionProbe probe_;
  LatencyHistogram wake_latency_;
  LatencyHistogram compute_time_;
  std::atomic<std::uint64_t> ticks_done_{0};
  std::uint64_t next_tick_ = 0;           // the first tick of the next run()
  std::uint64_t scene_damped_ticks_ = 0;  // several joints: ticks any wall's controller damped
  StatePublisher publisher_;
  kinematics::Vec3 task_force_ = kinematics::Vec3::Zero();  // several joints: what acted this tick
  LiveStatus live_;
  using K = base::CounterKind;
  std::array<base::Counter, kLoopCounterCount> counters_{{
      {"overruns", K::kAnomaly, "ticks that finished after the next deadline"},
      {"missed_ticks", K::kAnomaly, "whole periods skipped after a tick that ended that late"},
      {"stale_ticks", K::kAnomaly, "ticks without a new position (the last one held)"},
      {"sequence_gaps", K::kAnomaly, "times the device's own sequence skipped samples"},
      {"samples_missed", K::kAnomaly, "samples those gaps skipped in all"},
      {"contact_ticks", K::kCount, "ticks in contact with the wall"},
      {"saturated_ticks", K::kCount, "ticks whose force was limited to device.max_force"},
      {"unarmed_ticks", K::kCount, "ticks inside the wall before it was first left"},
      {"reloads", K::kCount, "control laws swapped in at a tick boundary"},
  }};
};

}  // namespace hapticd::loop
