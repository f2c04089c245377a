// The state block (docs/clients.md): the servo loop's state at every tick, in shared memory
// the daemon writes and any number of clients read with no system call per sample. The daemon
// passes its descriptor (a sealed memfd) with the control socket's answer to {"cmd": "state"}
// (SCM_RIGHTS); a reader maps it read-only. A slow or dead reader never slows the loop: the
// loop overwrites the oldest slot, and the reader counts what it could not read in time.
//
// Layout 1, little-endian, shared by the daemon's writer (telemetry/state_block.h) and the
// readers (state_reader.h, the Python package's hapticd/state.py):
//   header (kStateHeaderBytes): StateHeader below; `head` counts the samples written, sample n
//     lives in slot n % slots
//   slot k at kStateHeaderBytes + k kStateSlotBytes: a sequence word (a sequence lock: 2n + 1
//     while sample n is being written into it, 2n + 2 once it is whole), then StateSample.
// A change of this layout is a new kStateLayout, listed in docs/clients.md.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace hapticd::client {

inline constexpr char kStateMagic[8] = {'H', 'A', 'P', 'T', 'S', 'T', 'A', 'T'};
inline constexpr std::uint32_t kStateLayout = 1;
inline constexpr std::uint32_t kStateHeaderBytes = 128;
inline constexpr std::uint32_t kStateSlotBytes = 192;

// One tick. Names after CRTK where one fits: q, qd, effort are measured_js; x measured_cp;
// v measured_cv; f setpoint_cf. Joints and axes past the device's are 0.
struct StateSample {
  std::uint64_t tick = 0;
  std::int64_t time_ns = 0;        // CLOCK_MONOTONIC when the tick woke
  double q[3] = {0, 0, 0};         // each joint's position as read (rad or m)
  double qd[3] = {0, 0, 0};        // each joint's velocity, backward difference (per s)
  double effort[3] = {0, 0, 0};    // each joint's torque or force written (N m or N)
  double x[3] = {0, 0, 0};         // task position (m); a device of one joint: x[0] = q[0]
  double v[3] = {0, 0, 0};         // task velocity, backward difference (m/s)
  double f[3] = {0, 0, 0};         // task force the walls commanded, as it acted (N)
  double observer_energy_j = 0.0;  // the passivity observers' energy, summed (J)
  std::uint32_t flags = 0;         // the tick log's TickFlag bits (telemetry/tick_record.h)
  std::uint32_t wall_contact = 0;  // bit i: wall i in contact
  std::uint32_t fault_cause = 0;   // the loop's fault on this tick, 0: none
  std::uint32_t reserved = 0;
};

struct StateHeader {
  char magic[8];
  std::uint32_t layout;
  std::uint32_t header_bytes;
  std::uint32_t slot_bytes;
  std::uint32_t slots;  // a power of two
  std::uint64_t sample_period_ns;
  std::uint32_t joints;
  std::uint32_t axes;               // task axes
  std::atomic<std::uint64_t> head;  // samples written so far
  std::uint8_t reserved[80];
};

// A slot. The sample is held as words, each read and written as a relaxed atomic, so a read
// that races a write is no data race (the sequence says whether to keep what it read).
inline constexpr std::size_t kStateWords = sizeof(StateSample) / 8;
struct StateSlot {
  std::atomic<std::uint64_t> sequence;
  std::atomic<std::uint64_t> words[kStateWords];
};

static_assert(sizeof(StateSample) == 184 && sizeof(StateSample) % 8 == 0);
static_assert(offsetof(StateSample, time_ns) == 8 && offsetof(StateSample, q) == 16 &&
              offsetof(StateSample, qd) == 40 && offsetof(StateSample, effort) == 64 &&
              offsetof(StateSample, x) == 88 && offsetof(StateSample, v) == 112 &&
              offsetof(StateSample, f) == 136 && offsetof(StateSample, observer_energy_j) == 160 &&
              offsetof(StateSample, flags) == 168 && offsetof(StateSample, wall_contact) == 172 &&
              offsetof(StateSample, fault_cause) == 176);
static_assert(sizeof(StateHeader) == kStateHeaderBytes && offsetof(StateHeader, head) == 40);
static_assert(sizeof(StateSlot) == kStateSlotBytes);
static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "shared between processes");

}  // namespace hapticd::client
