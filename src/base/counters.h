// Named counters, one registry for the loop and every driver (PX4's perf_counter in spirit):
// whoever counts owns its Counter objects, declared once with a name, a kind and one line of
// meaning; the RT thread only adds to them (a relaxed atomic add: no lock, no allocation);
// the run summary, `hapticctl status`, the control socket's JSON and the tick log's events
// read them all through a CounterRegistry, so a driver's health shows wherever the loop's does
// (docs/architecture.md).
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::base {

enum class CounterKind : std::uint8_t {
  kCount,    // ordinary work, for context: frames received, reports read, ticks in contact
  kAnomaly,  // something unusual that the run survived: a malformed frame, a missed edge, a
             // stale tick, a sequence gap. Shown wherever the run's health is shown.
};

// "count" or "anomaly".
std::string_view to_string(CounterKind kind) noexcept;

class Counter {
 public:
  // Not RT-safe. `name` (snake_case) and `meaning` must outlive the counter (string literals).
  constexpr Counter(std::string_view name, CounterKind kind, std::string_view meaning) noexcept
      : name_(name), meaning_(meaning), kind_(kind) {}
  Counter(const Counter&) = delete;
  Counter& operator=(const Counter&) = delete;

  // RT-safe: called every tick.
  void add(std::uint64_t n = 1) noexcept { value_.fetch_add(n, std::memory_order_relaxed); }
  // RT-safe. For a count kept elsewhere and published here (a level, a running total).
  void set(std::uint64_t v) noexcept { value_.store(v, std::memory_order_relaxed); }
  // Any thread.
  std::uint64_t value() const noexcept { return value_.load(std::memory_order_relaxed); }
  std::string_view name() const noexcept { return name_; }
  std::string_view meaning() const noexcept { return meaning_; }
  CounterKind kind() const noexcept { return kind_; }

 private:
  std::atomic<std::uint64_t> value_{0};
  std::string_view name_;
  std::string_view meaning_;
  CounterKind kind_;
};

// One counter's value as read off the RT thread, with where it comes from.
struct CounterReading {
  std::string source;  // "loop", or the driver's name ("can", "hid", "gpio", "sim")
  std::string name;
  CounterKind kind = CounterKind::kCount;
  std::uint64_t value = 0;
  std::string meaning;
};

// Every counter of a run, in the order its owners were added. Not RT-safe: built before the
// loop, read off the RT thread; the counters it lists must outlive it.
class CounterRegistry {
 public:
  void add(std::string_view source, std::span<const Counter> counters);
  void add(std::string_view source, std::span<const Counter* const> counters);
  // Allocates. Each counter's current value.
  std::vector<CounterReading> read() const;

 private:
  struct Entry {
    std::string source;
    const Counter* counter;
  };
  std::vector<Entry> entries_;
};

// Not RT-safe. The anomalies among `readings` that are not zero, as "3 malformed_reports,
// 1 missed_edges" ("none" when there are none): what a summary line shows.
std::string anomalies_text(std::span<const CounterReading> readings);

}  // namespace hapticd::base
