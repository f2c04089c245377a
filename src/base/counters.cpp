#include "base/counters.h"

namespace hapticd::base {

std::string_view to_string(CounterKind kind) noexcept {
  return kind == CounterKind::kAnomaly ? "anomaly" : "count";
}

void CounterRegistry::add(std::string_view source, std::span<const Counter> counters) {
  for (const Counter& c : counters) entries_.push_back({std::string(source), &c});
}

void CounterRegistry::add(std::string_view source, std::span<const Counter* const> counters) {
  for (const Counter* c : counters) entries_.push_back({std::string(source), c});
}

std::vector<CounterReading> CounterRegistry::read() const {
  std::vector<CounterReading> out;
  out.reserve(entries_.size());
  for (const Entry& e : entries_) {
    out.push_back({e.source, std::string(e.counter->name()), e.counter->kind(), e.counter->value(),
                   std::string(e.counter->meaning())});
  }
  return out;
}

std::string anomalies_text(std::span<const CounterReading> readings) {
  std::string text;
  for (const CounterReading& r : readings) {
    if (r.kind != CounterKind::kAnomaly || r.value == 0) continue;
    if (!text.empty()) text += ", ";
    text += std::to_string(r.value) + " " + r.name;
  }
  return text.empty() ? "none" : text;
}

}  // namespace hapticd::base
