// Shared helpers for the telemetry tests: a scratch directory, recognisable records, and
// whole-file byte I/O.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "telemetry/log_format.h"
#include "telemetry/tick_record.h"

namespace hapticd::telemetry::test {

// A fresh directory under the system temp dir, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "hapticd-telemetry-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// Every field derived from the tick, so a record shuffled, torn or misplaced shows up.
inline TickRecord make_record(std::uint64_t tick) {
  TickRecord r;
  r.tick = tick;
  r.scheduled_ns = static_cast<std::int64_t>(tick) * 1'000'000;
  r.wake_latency_ns = static_cast<std::int32_t>(tick % 997) - 400;
  r.compute_ns = static_cast<std::int32_t>(tick % 13) * 1000;
  r.position = 0.001 * static_cast<double>(tick);
  r.penetration = -0.5 * static_cast<double>(tick);
  r.velocity = 1.0 / (1.0 + static_cast<double>(tick));
  r.force_computed = 3.25 * static_cast<double>(tick % 101);
  r.force_commanded = -r.force_computed;
  r.flags = static_cast<std::uint32_t>(tick) & 0x7fu;
  r.device_status = static_cast<std::uint32_t>(tick * 2654435761u);
  r.sample_time_ns = static_cast<std::int64_t>(tick) * 999'983;
  r.sequence = static_cast<std::uint32_t>(tick * 3);
  r.fault_cause = static_cast<std::uint8_t>(tick % 7);
  r.fault_class = static_cast<std::uint8_t>(tick % 3);
  r.sequence_gap = static_cast<std::uint16_t>(tick % 5);
  r.fault_code = static_cast<std::uint32_t>(tick * 40503u);
  r.observer_energy_j = 0.25 - 1e-3 * static_cast<double>(tick);
  r.passivity_damping = static_cast<double>(tick % 4);
  r.joint_position[0] = 0.002 * static_cast<double>(tick);
  r.joint_position[1] = -0.003 * static_cast<double>(tick);
  r.joint_force[0] = 0.5 * static_cast<double>(tick % 11);
  r.joint_force[1] = -0.25 * static_cast<double>(tick % 7);
  r.task_position[0] = 1e-4 * static_cast<double>(tick);
  r.task_position[1] = 2e-4 * static_cast<double>(tick);
  r.task_position[2] = 0.11 + 1e-5 * static_cast<double>(tick);
  r.joints = static_cast<std::uint8_t>(1 + tick % 3);
  r.deepest_wall = static_cast<std::uint8_t>(tick % 8);
  r.wall_contact = static_cast<std::uint8_t>(tick * 37u);
  r.pose_status = static_cast<std::uint8_t>(tick % 4);
  return r;
}

inline std::vector<TickRecord> make_records(std::uint64_t first, std::size_t n) {
  std::vector<TickRecord> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(make_record(first + i));
  return out;
}

inline bool same_bytes(const TickRecord& a, const TickRecord& b) {
  return std::memcmp(&a, &b, sizeof(TickRecord)) == 0;
}

inline ::testing::AssertionResult records_identical(const std::vector<TickRecord>& got,
                                                    const std::vector<TickRecord>& want) {
  if (got.size() != want.size()) {
    return ::testing::AssertionFailure()
           << "got " << got.size() << " records, want " << want.size();
  }
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (!same_bytes(got[i], want[i])) {
      return ::testing::AssertionFailure()
             << "record " << i << " differs (tick " << got[i].tick << " vs " << want[i].tick << ")";
    }
  }
  return ::testing::AssertionSuccess();
}

inline std::vector<std::byte> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(chars.size());
  if (!chars.empty()) std::memcpy(out.data(), chars.data(), chars.size());
  return out;
}

inline void write_bytes(const std::string& path, std::span<const std::byte> bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

inline LogHeader sample_header() {
  LogHeader h;
  h.sample_period_s = 0.001;
  h.start_unix_ns = 1'700'000'000'123'456'789;
  h.clock_mode = kClockModeFreerun;
  h.config_text = "loop:\n  rate_hz: 1000\n  clock: freerun\nwall:\n  stiffness: 2000 # N/m\n";
  return h;
}

}  // namespace hapticd::telemetry::test
