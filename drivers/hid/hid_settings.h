// The HID driver's settings, the section device.hid (read and validated by hid_section.cpp;
// every key is documented in config/hid-report.yaml and config/hid-pid.yaml). Plain values.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "config/schema_reader.h"
#include "drivers/hid/pid_protocol.h"
#include "drivers/hid/report_layout.h"

namespace hapticd::drivers::hid {

enum class Backend : std::uint8_t { kHidraw, kLibusb };
enum class Profile : std::uint8_t { kReport, kPid };
const char* to_string(Backend b) noexcept;
const char* to_string(Profile p) noexcept;

// Which attached device: every key given must match; `path` alone overrides the rest.
struct Selector {
  std::optional<std::uint16_t> vendor_id, product_id;
  std::string serial;                              // empty: any
  std::optional<int> interface;                    // USB interface number
  std::optional<std::uint16_t> usage_page, usage;  // the top-level collection's
  std::string path;  // a hidapi path (/dev/hidrawN, or bus-port:cfg.intf)
};

// One joint's position: an input usage and the SI positions at its logical ends.
struct PidPosition {
  std::uint32_t usage = kGenericDesktopX;
  double min = 0.0;  // SI position at the axis' logical minimum
  double max = 0.0;  // ... and at its logical maximum
};

struct PidSettings {
  std::vector<PidPosition> positions;  // one per joint (`position`, or the list `positions`)
  std::uint32_t sequence_usage = 0;    // an input usage beside the axes read as a counter; 0: none
  double force_full_scale = 0.0;       // N (N m) at the Magnitude's logical maximum
  double gain = 1.0;                   // Device Gain, a fraction of its logical maximum, (0, 1]
  // One joint: one effect, Direction Enable set, this polar Direction (where the force comes
  // from: 270 = +X).
  double direction_deg = 270.0;
  // Two joints: one effect per axis (Axes Enable X, then Y), Direction Enable clear, joint i's
  // effect's own Direction instance i at directions_deg[i], mapped from 0..360 onto the field's
  // logical range (docs/drivers/hid.md, "Two axes"). Empty for one joint.
  std::vector<double> directions_deg;
  double effect_duration_ms = 0.0;  // 0: infinite; else each effect stops unless restarted
  std::uint32_t fault_mask = kPidDefaultFaultMask;  // PidStatus bits that fault the loop
  std::size_t joints() const noexcept { return positions.size(); }
};

struct Limits {
  int out_queue = 8;              // output reports queued between the RT thread and the device
  int out_queue_full_fault = 10;  // consecutive ticks with that queue full that fault the loop
  double timeout_ms = 1000.0;     // answers to feature and descriptor requests
};

struct HidSettings final : config::DriverSettings {
  Selector select;
  Backend backend = Backend::kHidraw;
  Profile profile = Profile::kReport;
  double poll_interval_ms = 1.0;  // the interrupt endpoints' polling interval (bInterval)
  // The device sends its input report only when a value changes (and again after a while of
  // none), as most joysticks, wheels and OpenFFBoard do: a tick without a report is the same
  // position, and a device silent for longer than liveness_ms is a transport fault (hung
  // firmware). false: one report a period, and the loop's safety.stale_fault_ticks applies.
  bool reports_on_change = false;
  double liveness_ms = 250.0;
  Limits limits;
  ReportProfileLayout report;  // profile report
  PidSettings pid;             // profile pid
  int writer_priority = 0;     // SCHED_FIFO of the output thread (loop.rt_priority - 1)
};

// Output reports a tick carrying the force: one (profile report, or pid of one joint), or one
// Set Constant Force per joint (pid of two).
std::size_t force_reports_per_tick(const HidSettings& s) noexcept;

// Whole samples between write() and the force acting, as the gate analyses them: a tick's n
// force reports go out one a polling interval, the last up to n P after the write, and its
// answer takes up to one more to come back, so the answer to the command of tick k is read at
// tick k + ceil((n + 1) P / T), one tick later than an in-process device would give it. 1 at
// 1 kHz with bInterval 1 ms and one report (docs/drivers/hid.md).
int declared_delay_samples(const HidSettings& s, double sample_period_s) noexcept;

// Not RT-safe. Reads device.hid with the config library's schema reader, so every problem is
// reported as "FILE:LINE: device.hid.key: what" and an unknown key is never silently ignored;
// validation that spans keys (overlapping fields, fields past the report, a force scale that
// cannot reach device.max_force) is reported at the key that must change. The HidSettings, or
// null after reporting every problem through `section`.
std::shared_ptr<const config::DriverSettings> read_hid_section(config::schema::MapReader& section,
                                                               const config::Config& cfg);

}  // namespace hapticd::drivers::hid
