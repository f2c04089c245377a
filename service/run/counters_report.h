// The run's counter registry (base/counters.h) as the summary, `hapticctl status` and the
// control socket show it: the loop's counters and the driver's, read together, grouped by
// where they come from, with every anomaly that happened named with its meaning. Not RT-safe.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <ostream>
#include <span>
#include <string_view>
#include <vector>

#include "base/counters.h"
#include "drivers/device.h"
#include "loop/servo_loop.h"

namespace hapticd::service {

// The loop's counters (when there is a loop yet) and then the device's, read now.
std::vector<base::CounterReading> read_run_counters(const loop::ServoLoop* loop,
                                                    const Device& device);
// {"loop": {"overruns": 0, ...}, "hid": {"input_reports": 2998, ...}}
nlohmann::json counters_json(std::span<const base::CounterReading> counters);
// [{"source": "hid", "name": "long_reports", "value": 2, "meaning": "..."}]: the anomalies
// that happened (value > 0).
nlohmann::json anomalies_json(std::span<const base::CounterReading> counters);
// The value of one counter, 0 when there is none of that name.
std::uint64_t counter_value(std::span<const base::CounterReading> counters, std::string_view source,
                            std::string_view name);
// The summary's lines: one per source with its counters (the loop's too with `with_loop`; the
// summary shows those on lines of their own), then the anomalies (or "none").
void counters_text(std::span<const base::CounterReading> counters, std::ostream& os,
                   bool with_loop = false);

}  // namespace hapticd::service
