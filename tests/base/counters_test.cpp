// The counter registry that the summary, `hapticctl status` and the tick log's events list: a
// counter keeps what was added on the RT thread without allocating, the registry reads every
// owner's counters in the order they were added, and a summary line names only the anomalies.
#include <gtest/gtest.h>

#include <array>

#include "alloc_counter.h"
#include "base/counters.h"

namespace hapticd::base {
namespace {

using K = CounterKind;

TEST(Counters, AddingOnTheRtThreadAllocatesNothing) {
  Counter c("frames", K::kCount, "frames received");
  const hapticd::testing::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) c.add();
  c.add(5);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(c.value(), 1005u);
  c.set(7);
  EXPECT_EQ(c.value(), 7u);
}

TEST(Counters, TheRegistryListsEveryOwnersCountersInOrderWithTheirSource) {
  std::array<Counter, 2> loop{{{"stale_ticks", K::kAnomaly, "ticks without a new position"},
                               {"contact_ticks", K::kCount, "ticks in contact"}}};
  std::array<Counter, 1> driver{{{"missed_edges", K::kAnomaly, "encoder edges missed"}}};
  CounterRegistry registry;
  registry.add("loop", loop);
  registry.add("gpio", driver);
  loop[1].add(40);
  driver[0].add(3);
  const auto r = registry.read();
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].source, "loop");
  EXPECT_EQ(r[0].name, "stale_ticks");
  EXPECT_EQ(r[1].value, 40u);
  EXPECT_EQ(r[2].source, "gpio");
  EXPECT_EQ(r[2].kind, K::kAnomaly);
  EXPECT_EQ(r[2].meaning, "encoder edges missed");
  // Values are read when asked, not when registered.
  driver[0].add();
  EXPECT_EQ(registry.read()[2].value, 4u);
}

TEST(Counters, TheSummaryLineNamesOnlyAnomaliesThatHappened) {
  std::array<Counter, 3> c{{{"input_reports", K::kCount, "reports"},
                            {"short_reports", K::kAnomaly, "too short"},
                            {"long_reports", K::kAnomaly, "too long"}}};
  CounterRegistry registry;
  registry.add("hid", c);
  EXPECT_EQ(anomalies_text(registry.read()), "none");
  c[0].add(100);  // ordinary work is no anomaly
  EXPECT_EQ(anomalies_text(registry.read()), "none");
  c[2].add(2);
  EXPECT_EQ(anomalies_text(registry.read()), "2 long_reports");
  c[1].add();
  EXPECT_EQ(anomalies_text(registry.read()), "1 short_reports, 2 long_reports");
  EXPECT_EQ(to_string(K::kAnomaly), "anomaly");
  EXPECT_EQ(to_string(K::kCount), "count");
}

}  // namespace
}  // namespace hapticd::base
