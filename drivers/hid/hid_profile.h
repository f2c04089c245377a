// What differs between the two ways a HID device takes a force (device.hid.profile): the
// start-up and shut-down sequences, and the bytes of each tick. The Device (hid_device.h) owns
// the lifecycle, the draining of input reports, the counters and the fault policy, and calls
// these. Configuration-time calls throw DeviceError; the RT calls never block, allocate,
// lock, log or throw.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "base/joints.h"
#include "drivers/hid/hid_settings.h"
#include "drivers/hid/hid_transport.h"

namespace hapticd::drivers::hid {

// What one input report turned out to be.
enum class InputKind : std::uint8_t {
  kPosition,  // a sample: position (and sequence, velocity, status where configured)
  kState,     // a status-only report (PID State): status updated
  kOther,     // a report of another id: counted, ignored
  kTooShort,  // our id, shorter than its layout: counted as malformed
  kTooLong,   // our id, longer than the device declares it: counted as malformed
};

struct Decoded {
  std::array<double, base::kMaxJoints> position{};  // joint i's is entry i
  double velocity = 0.0;
  std::uint32_t sequence = 0;
  std::uint32_t status = 0;  // the profile's status bits, kept across reports
  bool has_sequence = false;
  bool has_velocity = false;
};

// Zero force on every joint: what the enables send first.
inline constexpr std::array<double, base::kMaxJoints> kZeroForce{};

class HidProfile {
 public:
  virtual ~HidProfile() = default;

  // Not RT-safe. The device is open: check it can do what the profile needs (its report
  // descriptor), prepare every report, and leave its output off.
  virtual void configure(HidTransport& t) = 0;
  // After configure: "report profile, input report 1 ..." for the device description.
  virtual std::string summary() const = 0;
  virtual std::uint64_t sequence_modulus() const = 0;
  // Not RT-safe. Output on with zero force (an enable left half done is undone by disable).
  virtual void enable(HidTransport& t) = 0;
  // Not RT-safe, never throws: what remains after the safe reports (feature switches, freeing
  // the effect).
  virtual void disable(HidTransport& t) noexcept = 0;
  // The output reports that leave the device with zero force and its output off.
  virtual std::vector<std::vector<std::uint8_t>> safe_reports() const = 0;

  // RT-safe: called every tick. Decodes one input report into `d`.
  virtual InputKind decode(std::span<const std::uint8_t> report, Decoded& d) noexcept = 0;
  // RT-safe: called every tick. The status bits that mean the device has faulted.
  virtual std::uint32_t fault_bits(std::uint32_t status) const noexcept = 0;
  // RT-safe: called every tick. A report to send before this tick's force (a firmware
  // watchdog's refresh), or an empty span.
  virtual std::span<const std::uint8_t> before_force() noexcept = 0;
  // RT-safe: called every tick. The output reports carrying `forces`, one per joint the profile
  // drives (joints()), joint i's entry i: one report (profile report), or one per joint
  // (profile pid, force_reports_per_tick), sent in order.
  virtual std::span<const std::span<const std::uint8_t>> force_reports(
      std::span<const double> forces) noexcept = 0;
  // The joints the profile drives: the layout's (report), one (pid).
  virtual std::size_t joints() const noexcept = 0;
  // Not RT-safe: "status 0x05: ..." for a device fault with these status bits.
  virtual std::string describe_status(std::uint32_t status) const = 0;
};

std::unique_ptr<HidProfile> make_report_profile(const HidSettings& s);
std::unique_ptr<HidProfile> make_pid_profile(const HidSettings& s, double sample_period_s);

// Not RT-safe. Hands `report` to the transport and waits for it to go out; throws DeviceError
// naming `what` when the device does not take it within `timeout`.
void send_now(HidTransport& t, std::span<const std::uint8_t> report, const std::string& what,
              std::chrono::milliseconds timeout);

}  // namespace hapticd::drivers::hid
