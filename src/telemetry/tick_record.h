// One fixed-size record per tick, written by the RT thread into the SPSC ring and appended
// to the binary log by the writer thread. The layout is part of the log format (version 5):
// little-endian, no padding, 200 bytes. Version 1 to 4 logs (72-, 96-, 112- and 176-byte
// records, the first bytes of this layout) are still read, with the later fields zero.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace hapticd::telemetry {

enum TickFlag : std::uint32_t {
  kFlagContact = 1u << 0,        // penetration > 0 at this sample
  kFlagSaturated = 1u << 1,      // |command| was limited to device.max_force
  kFlagFault = 1u << 2,          // the loop faulted on this tick (zero force commanded)
  kFlagOverrun = 1u << 3,        // this tick finished after the next deadline
  kFlagNoPullClamped = 1u << 4,  // wall.no_pull turned a pulling force into zero
  kFlagStale = 1u << 5,          // the device had no new position this tick
  kFlagUnarmed = 1u << 6,      // started inside the wall: zero force until the device first leaves
  kFlagNonFinite = 1u << 7,    // the controller computed a non-finite force: zero commanded, fault
  kFlagSequenceGap = 1u << 8,  // the device's sequence skipped samples before this one
  kFlagNoPosition = 1u << 9,   // no position to act on yet: the controller was not stepped
  kFlagPassivityDamped = 1u << 10,  // the passivity controller added damping on this tick
  kFlagStepped = 1u << 11,          // the controller and the passivity observer ran on this tick
  // The device reports on change and said nothing this tick: its last position, still
  // current, was held (no new measurement, not stale). Logs before this bit existed leave it 0.
  kFlagHeld = 1u << 12,
  // The runaway guard faulted this tick: deeper than safety.max_penetration (or 1.5
  // max_force / K) while the wall pushed at max_force. Logs before this bit leave it 0.
  kFlagRunaway = 1u << 13,
  // The direction check's tick (docs/devices.md): the wall not armed yet; the force commanded
  // is the check's pulse (or zero while it waits for rest). Logs before this bit leave it 0.
  kFlagProbe = 1u << 14,
  // Version 5: a client's commanded force was held off this tick by its energy observer
  // (loop/client_force.h). Logs before this bit leave it 0.
  kFlagClientForceLimited = 1u << 15,
};

// A record that is not a tick but an event at a tick boundary (TickRecord::marker): `tick` is
// the first tick the event applies to, the other fields are those of the tick before it.
enum TickMarker : std::uint32_t {
  kMarkerNone = 0,  // an ordinary tick
  // A live reload swapped the control law in from `tick` on. Version 5, a device of several
  // joints: `sequence` says which running wall each new wall went on from (continues_code).
  kMarkerReloadAccepted = 1,
  kMarkerReloadRefused = 2,  // a live reload was refused; the law in force stays
  kMarkerRearmed = 3,  // output enabled again after a cleared fault: a fresh law from `tick` on
  // Version 5: a client moved wall `deepest_wall` to `task_position` (m) from `tick` on (its
  // point slides there at safety.max_wall_speed); the other fields are zero.
  kMarkerWallMoved = 4,
};

// Which running wall each of a swap's walls goes on from, as a reload marker carries it
// (version 5): bits 4i..4i+3 are 1 + the running wall's index for wall i, 0 a new wall (8
// walls at most, config::kMaxWalls). RT-safe.
constexpr std::uint32_t continues_code(const int* continues, std::size_t walls) noexcept {
  std::uint32_t code = 0;
  for (std::size_t i = 0; i < walls && i < 8; ++i) {
    code |= static_cast<std::uint32_t>((continues[i] + 1) & 0xf) << (4 * i);
  }
  return code;
}
constexpr int continued_from(std::uint32_t code, std::size_t wall) noexcept {
  return static_cast<int>((code >> (4 * wall)) & 0xf) - 1;
}

struct TickRecord {
  std::uint64_t tick = 0;
  std::int64_t scheduled_ns = 0;     // deadline of this tick since loop start (freerun: k*T)
  std::int32_t wake_latency_ns = 0;  // wake time minus deadline (freerun: 0, nothing waits)
  std::int32_t compute_ns = 0;       // read+step+write time (freerun: 0, see the summary)
  double position = 0.0;             // x as read from the device
  double penetration = 0.0;          // p = n (x - x0)
  double velocity = 0.0;             // backward-difference estimate (x_k - x_{k-1}) / T
  double force_computed = 0.0;       // f_k = E(z)[xi(p_ve)]_k, before delay and limits
  double force_commanded = 0.0;      // u written to the device: -n f_{k-d}, clamped, saturated
  std::uint32_t flags = 0;           // TickFlag bits
  std::uint32_t device_status = 0;   // PositionSample::status
  // Version 2.
  std::int64_t sample_time_ns = 0;  // when the device measured x (CLOCK_MONOTONIC), 0: unknown
  std::uint32_t sequence = 0;       // the device's sample counter (low 32 bits), 0: none
  std::uint8_t fault_cause = 0;     // loop::FaultCause of the fault on this tick, 0: none
  std::uint8_t fault_class = 0;     // FaultClass of a device fault: 1 transport, 2 device
  std::uint16_t sequence_gap = 0;   // samples missing before this one (saturates at 65535)
  std::uint32_t fault_code = 0;     // the driver's code of that fault (errno, EMCY, axis error)
  std::uint32_t marker = 0;         // TickMarker: 0 for a tick, else an event record
  // Version 3.
  double observer_energy_j = 0.0;  // the passivity observer's energy E_k (J), 0 when off
  double passivity_damping = 0.0;  // damping the passivity controller added (N s/m), 0: none
  // Version 4: a device of several joints (docs/kinematics.md). `position` and
  // `force_commanded` are joint 1's; penetration, velocity and force_computed the deepest
  // wall's (its coordinate n . (x - p)); observer_energy_j the sum of the walls' observers,
  // passivity_damping the most any of them added.
  double joint_position[2] = {0.0, 0.0};      // joints 2 and 3 as read (0 beyond the device's)
  double joint_force[2] = {0.0, 0.0};         // the torques written to joints 2 and 3
  double task_position[3] = {0.0, 0.0, 0.0};  // x = fk(q) (m), 0 for a device of one joint
  std::uint8_t joints = 0;        // the device's joints; 0 in logs before version 4 (one)
  std::uint8_t deepest_wall = 0;  // the wall penetration, velocity and force_computed describe
  std::uint8_t wall_contact = 0;  // bit i: wall i in contact
  std::uint8_t pose_status = 0;   // kinematics::Status of the tick's pose, 0: ok
  std::uint32_t reserved = 0;
  // Version 5: the force a client commanded (servo_cf) that this tick added to the walls',
  // before the joints' saturation (task space, N; 0 when none).
  double client_force[3] = {0.0, 0.0, 0.0};
};

static_assert(std::is_trivially_copyable_v<TickRecord>);
static_assert(sizeof(TickRecord) == 200, "TickRecord is part of the log format");

}  // namespace hapticd::telemetry
