#include "drivers/hid/hid_settings.h"

#include <algorithm>

#include "drivers/driver_context.h"

namespace hapticd::drivers::hid {

const char* to_string(Backend b) noexcept { return b == Backend::kHidraw ? "hidraw" : "libusb"; }
const char* to_string(Profile p) noexcept { return p == Profile::kReport ? "report" : "pid"; }

std::size_t force_reports_per_tick(const HidSettings& s) noexcept {
  return s.profile == Profile::kPid ? std::max<std::size_t>(1, s.pid.joints()) : 1;
}

int declared_delay_samples(const HidSettings& s, double sample_period_s) noexcept {
  // The round trip (n + 1) P as round_trip_delay_samples takes it: half of it each way.
  const double n = static_cast<double>(force_reports_per_tick(s));
  return round_trip_delay_samples((n + 1.0) / 2.0 * s.poll_interval_ms, sample_period_s);
}

}  // namespace hapticd::drivers::hid
