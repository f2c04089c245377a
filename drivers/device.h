// The one seam between control and hardware (docs/devices.md). The controller never sees a
// transport; a driver never sees the controller. The lifecycle is an explicit state machine,
// enforced here for every driver (ros2_control's lifecycle, PX4's self-checking drivers):
//
//   UNCONFIGURED --configure()--> CONFIGURED --enable()--> ACTIVE --disable()--> CONFIGURED
//         ^                           |  ^                   |  fault (transport or device)
//         +-------- close() ----------+  +-- clear_fault() --+--> FAULTED (zero force, latched)
//
// configure() opens the transport and identifies the device with output disabled, so the gate
// can run against what the device declares before anything is enabled; a refused gate leaves
// it CONFIGURED and safe. An enable() that fails halfway is undone. close() is allowed from
// every state and disables output first. Illegal transitions throw DeviceError.
//
// A driver implements the protected on_*() hooks; this class owns the state, refuses what the
// state does not allow, latches faults and keeps the last command. On the RT thread, read()
// and write() never block, allocate, lock, log or throw.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "base/counters.h"
#include "base/joints.h"

namespace hapticd {

enum class DeviceState : std::uint8_t { kUnconfigured, kConfigured, kActive, kFaulted };

// "unconfigured", "configured", "active", "faulted".
std::string_view to_string(DeviceState state) noexcept;

// What an RT-side device call achieved. Counting and fault policy belong to the loop.
enum class IoStatus : std::uint8_t {
  kOk,              // read: a fresh sample; write: command accepted by the transport
  kNoNewData,       // read: nothing new since the last tick (the loop counts stale ticks)
  kTransportFault,  // the transport failed: I/O error, bus-off, device gone, queue full
  kDeviceFault,     // the device reported a fault: status bit, EMCY, axis error
};

enum class FaultClass : std::uint8_t { kNone, kTransport, kDevice };

// A latched fault: its class and a driver-specific code (an errno, a CiA 402 EMCY error code,
// an ODrive axis error, HID status bits), recorded in the tick log and the run summary.
struct DeviceFault {
  FaultClass fault_class = FaultClass::kNone;
  std::uint32_t code = 0;
};

// Bits of PositionSample::flags: which optional fields the transport filled in.
enum SampleFlag : std::uint8_t {
  kSampleHasTime = 1u << 0,      // time_ns is when the device or kernel measured it
  kSampleHasSequence = 1u << 1,  // sequence is the device's own counter
  kSampleHasVelocity = 1u << 2,  // velocity is the device's own estimate
  // The device reports only on change and said nothing this tick: the position is the last
  // one it reported, still current (not stale), but no new measurement either.
  kSampleHeld = 1u << 3,
};

struct PositionSample {
  double position = 0.0;       // axis coordinate (m or rad), device frame
  std::int64_t time_ns = 0;    // CLOCK_MONOTONIC ns of the measurement (kSampleHasTime)
  std::uint64_t sequence = 0;  // the device's sample counter (kSampleHasSequence)
  double velocity = 0.0;       // the device's own velocity estimate (kSampleHasVelocity)
  std::uint32_t status = 0;    // driver-specific status bits, recorded in the tick log
  std::uint8_t flags = 0;      // SampleFlag bits
  // Samples of the device's sequence this read took in: the newest and the older ones it
  // replaced (a device faster than the loop). The loop counts a gap only beyond them.
  std::uint32_t samples = 1;
};

// What configure() learned about the device: the numbers the gate analyses.
struct DeviceInfo {
  std::string description;             // "sim", "hid 1209:ffb0 serial 42", "cia402 node 3 on can0"
  int transport_delay_samples = 0;     // whole samples between write() and the force acting
  std::uint64_t sequence_modulus = 0;  // where the device's sequence wraps (2^8, 2^16...); 0: none
  // Joints the device drives, 1..base::kMaxJoints: read() fills one sample per joint, write()
  // takes one force per joint, in this order.
  std::size_t joints = 1;
};

// Thrown by the non-RT lifecycle calls. The service maps it to exit code 4.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Device {
 public:
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // Not RT-safe. UNCONFIGURED -> CONFIGURED: opens the transport and identifies the device,
  // output disabled. On failure the transport is closed again and the state stays UNCONFIGURED.
  void configure();
  // Not RT-safe. CONFIGURED -> ACTIVE. On failure the driver's disable runs and the state
  // stays CONFIGURED: an enable is never left half done.
  void enable();
  // Not RT-safe, never throws. ACTIVE -> CONFIGURED: zero force, output off. In FAULTED it
  // makes sure output is off and the fault stays latched; elsewhere it does nothing.
  void disable() noexcept;
  // Not RT-safe. FAULTED -> CONFIGURED (CiA 402 fault reset, clearing ODrive errors...).
  void clear_fault();
  // Not RT-safe, never throws. Any state -> UNCONFIGURED: output off, transport closed.
  void close() noexcept;

  // Any thread.
  DeviceState state() const noexcept { return state_.load(std::memory_order_acquire); }
  bool output_enabled() const noexcept { return state() == DeviceState::kActive; }
  // Valid from CONFIGURED on.
  const DeviceInfo& info() const noexcept { return info_; }
  // The latched fault (class kNone unless FAULTED).
  DeviceFault fault() const noexcept { return fault_; }
  // The force last handed to the transport for `joint` (0 after disable, close or a fault).
  double last_command(std::size_t joint = 0) const noexcept {
    return joint < base::kMaxJoints ? last_command_[joint].load(std::memory_order_relaxed) : 0.0;
  }
  // Not RT-safe. One sentence about the latched fault, naming its cause and code.
  std::string describe_fault() const;
  virtual std::string_view driver_name() const noexcept = 0;
  // Not RT-safe, valid from CONFIGURED on. What configure found that the person running it
  // should know but that does not stop it (an optional object the device lacks, a setting seen
  // on the wire), one sentence each.
  virtual std::vector<std::string> notices() const { return {}; }
  // Any thread. The driver's own counters (base/counters.h): what it received and sent, and
  // every anomaly it survived (missed encoder edges, malformed reports...). The run's counter
  // registry lists them beside the loop's; empty for a driver with nothing to count.
  virtual std::span<const base::Counter> counters() const noexcept { return {}; }

  // RT-safe: called every tick. The newest sample of each joint (out.size() == info().joints),
  // draining whatever the transport queued. Allowed in CONFIGURED (output off) and ACTIVE; a
  // fault latches FAULTED and commands zero on every joint. `periods`: sample periods since
  // the previous read, more than one after the loop skipped some (a device whose time is the
  // loop's, the sim, lives through them too; a real one did anyway).
  IoStatus read(std::span<PositionSample> out, std::uint32_t periods = 1) noexcept;
  // RT-safe: called every tick. One force command per joint (N or N m, device frame;
  // forces.size() == info().joints). Only ACTIVE passes them on; in FAULTED only zero is passed
  // (returns the latched fault's status); in any other state it is refused as a transport
  // fault without touching the transport. A non-finite force on any joint, or a span of the
  // wrong size, is never passed on: zero is written on every joint and the device faults.
  IoStatus write(std::span<const double> forces) noexcept;
  // RT-safe. The same for a device of one joint.
  IoStatus read(PositionSample& out) noexcept { return read(std::span<PositionSample>(&out, 1)); }
  IoStatus write(double force) noexcept { return write(std::span<const double>(&force, 1)); }

  // RT-safe (it may sleep on a futex; it never allocates). For a driver whose write() hands
  // the command to a thread of its own (evdev's update thread): returns once that thread has
  // passed the newest command through the transport, so a paced loopback
  // (sim/peers/paced_device.h) waits for its simulated device alone after it. Default: write()
  // passed the command on itself.
  virtual void wait_output() const noexcept {}

  // Async-signal-safe: called from a crash handler, where nothing else can run. Only write(2)
  // (or an ioctl(2) that writes, as usbfs's bulk transfer) of prebuilt zero-force and disable
  // messages on already-open descriptors. Default: nothing (an in-process device has nothing
  // to stop once the process is gone).
  virtual void emergency_stop() noexcept {}

 protected:
  Device() = default;

  // Hooks, called only in the states above. on_configure returns what it learned.
  virtual DeviceInfo on_configure() = 0;
  virtual void on_enable() = 0;
  virtual void on_disable() noexcept = 0;  // zero force, output off; also after a fault
  virtual void on_clear_fault() {}         // device-side reset, then state CONFIGURED
  virtual void on_close() noexcept = 0;
  // out and forces hold exactly info().joints entries (checked before the call).
  virtual IoStatus on_read(std::span<PositionSample> out) noexcept = 0;
  virtual IoStatus on_write(std::span<const double> forces) noexcept = 0;
  // Not RT-safe. The sentence for a fault this driver latched (its code decoded).
  virtual std::string describe(const DeviceFault& fault) const = 0;

  // RT-safe. For a driver that learns of a fault outside read/write (e.g. while configuring
  // a drive during enable): latch it. read/write returning a fault status latch it themselves
  // with the code set here beforehand (or 0).
  void set_fault_code(std::uint32_t code) noexcept { pending_code_ = code; }
  // RT-safe. In on_read: the sample periods since the previous read (at least 1).
  std::uint32_t read_periods() const noexcept { return read_periods_; }

 private:
  // What the base refused itself, rather than the driver reporting it.
  enum class Refusal : std::uint8_t { kNone, kNonFinite, kJointCount };

  IoStatus latch(IoStatus status) noexcept;
  IoStatus refuse(Refusal why) noexcept;
  void write_zero() noexcept;
  void clear_commands() noexcept;
  void require(DeviceState expected, const char* call) const;

  std::atomic<DeviceState> state_{DeviceState::kUnconfigured};
  DeviceInfo info_;
  DeviceFault fault_;
  std::uint32_t pending_code_ = 0;
  Refusal refusal_ = Refusal::kNone;  // the latched fault is the base's refusal
  std::uint32_t read_periods_ = 1;
  std::array<std::atomic<double>, base::kMaxJoints> last_command_{};
};

}  // namespace hapticd
