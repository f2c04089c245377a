// One of a driver's counters by name, as the run summary and `hapticctl status` list it
// (Device::counters); a counter the driver does not have fails the test.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string_view>

#include "drivers/device.h"

namespace hapticd::testing {

inline std::uint64_t counter_value(const Device& d, std::string_view name) {
  for (const base::Counter& c : d.counters()) {
    if (c.name() == name) return c.value();
  }
  ADD_FAILURE() << "no counter " << name;
  return 0;
}

}  // namespace hapticd::testing
