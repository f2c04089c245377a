#include "drivers/hid/hid_settings.h"

#include "drivers/driver_context.h"

namespace hapticd::drivers::hid {

const char* to_string(Backend b) noexcept { return b == Backend::kHidraw ? "hidraw" : "libusb"; }
const char* to_string(Profile p) noexcept { return p == Profile::kReport ? "report" : "pid"; }

int declared_delay_samples(double poll_interval_ms, double sample_period_s) noexcept {
  return round_trip_delay_samples(poll_interval_ms, sample_period_s);
}

}  // namespace hapticd::drivers::hid
