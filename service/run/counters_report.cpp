#include "service/run/counters_report.h"

#include <string>

namespace hapticd::service {
namespace {

using nlohmann::json;

void padded(std::ostream& os, std::string_view label) {
  os << "  " << label << std::string(label.size() < 15 ? 15 - label.size() : 1, ' ');
}

}  // namespace

std::vector<base::CounterReading> read_run_counters(const loop::ServoLoop* loop,
                                                    const Device& device) {
  base::CounterRegistry registry;
  if (loop != nullptr) registry.add("loop", loop->counters());
  registry.add(device.driver_name(), device.counters());
  return registry.read();
}

json counters_json(std::span<const base::CounterReading> counters) {
  json j = json::object();
  for (const base::CounterReading& c : counters) j[c.source][c.name] = c.value;
  return j;
}

json anomalies_json(std::span<const base::CounterReading> counters) {
  json j = json::array();
  for (const base::CounterReading& c : counters) {
    if (c.kind != base::CounterKind::kAnomaly || c.value == 0) continue;
    j.push_back(
        {{"source", c.source}, {"name", c.name}, {"value", c.value}, {"meaning", c.meaning}});
  }
  return j;
}

std::uint64_t counter_value(std::span<const base::CounterReading> counters, std::string_view source,
                            std::string_view name) {
  for (const base::CounterReading& c : counters) {
    if (c.source == source && c.name == name) return c.value;
  }
  return 0;
}

void counters_text(std::span<const base::CounterReading> counters, std::ostream& os,
                   bool with_loop) {
  std::string source;
  for (const base::CounterReading& c : counters) {
    if (c.source == "loop" && !with_loop) continue;
    if (c.source != source) {
      if (!source.empty()) os << "\n";
      source = c.source;
      padded(os, source);
    } else {
      os << ", ";
    }
    os << c.name << " " << c.value;
  }
  if (!source.empty()) os << "\n";
  bool any = false;
  for (const base::CounterReading& c : counters) {
    if (c.kind != base::CounterKind::kAnomaly || c.value == 0) continue;
    if (any) {
      os << "                 ";
    } else {
      padded(os, "anomalies");
    }
    any = true;
    os << c.value << " " << c.name << " (" << c.source << ": " << c.meaning << ")\n";
  }
  if (!any) {
    padded(os, "anomalies");
    os << "none\n";
  }
}

}  // namespace hapticd::service
