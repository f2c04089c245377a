// GPIO in the kernel test machine: gpio-sim lines driven through their pull attribute arrive
// at a libgpiod (1.6 API) consumer as both-edge events with kernel timestamps, the way a
// quadrature encoder's lines reach hapticd's GPIO driver.
#include <gpiod.h>
#include <gtest/gtest.h>
#include <time.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "gpio_sim_chip.h"

namespace hapticd::kernel_test {
namespace {

using ChipPtr = std::unique_ptr<gpiod_chip, decltype(&gpiod_chip_close)>;

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1'000'000'000LL + ts.tv_nsec;
}

std::int64_t event_ns(const gpiod_line_event& event) {
  return event.ts.tv_sec * 1'000'000'000LL + event.ts.tv_nsec;
}

struct Edge {
  unsigned offset;
  int type;  // GPIOD_LINE_EVENT_RISING_EDGE or _FALLING_EDGE
  std::int64_t ns;
};

// The next event on any of the BULK's lines. The edge is raised by the sysfs write itself;
// the generous wait is for an emulated guest on a loaded host.
Edge next_edge(gpiod_line_bulk* bulk) {
  const timespec timeout{5, 0};
  gpiod_line_bulk ready;
  const int rv = gpiod_line_event_wait_bulk(bulk, &timeout, &ready);
  EXPECT_EQ(rv, 1) << "no edge within 5 s";
  if (rv != 1) return {~0u, -1, 0};
  gpiod_line* line = gpiod_line_bulk_get_line(&ready, 0);
  gpiod_line_event event{};
  EXPECT_EQ(gpiod_line_event_read(line, &event), 0);
  return {gpiod_line_offset(line), event.event_type, event_ns(event)};
}

TEST(GpioSim, ChipVisibleToLibgpiodWithLabelAndLineNames) {
  GpioSimChip sim(4, "hapticd-encoder", {"enc-a", "enc-b"});
  ChipPtr chip(gpiod_chip_open(sim.dev_path().c_str()), &gpiod_chip_close);
  ASSERT_NE(chip, nullptr) << sim.dev_path();
  EXPECT_STREQ(gpiod_chip_label(chip.get()), "hapticd-encoder");
  EXPECT_EQ(gpiod_chip_num_lines(chip.get()), 4u);
  gpiod_line* line = gpiod_chip_find_line(chip.get(), "enc-b");
  ASSERT_NE(line, nullptr);
  EXPECT_EQ(gpiod_line_offset(line), 1u);
}

TEST(GpioSim, PullChangesArriveAsBothEdgeEventsWithKernelTimestamps) {
  GpioSimChip sim(2);
  ChipPtr chip(gpiod_chip_open(sim.dev_path().c_str()), &gpiod_chip_close);
  ASSERT_NE(chip, nullptr);
  gpiod_line_bulk bulk;
  unsigned offsets[] = {0, 1};
  ASSERT_EQ(gpiod_chip_get_lines(chip.get(), offsets, 2, &bulk), 0);
  ASSERT_EQ(gpiod_line_request_bulk_both_edges_events(&bulk, "hapticd-kernel-test"), 0);
  EXPECT_EQ(gpiod_line_get_value(gpiod_line_bulk_get_line(&bulk, 0)), 0);

  // One quadrature cycle, forward: A rises, B rises, A falls, B falls.
  const std::int64_t before = monotonic_ns();
  const struct {
    unsigned line;
    bool up;
  } steps[] = {{0, true}, {1, true}, {0, false}, {1, false}};
  std::int64_t previous = before;
  for (const auto& step : steps) {
    sim.set_pull(step.line, step.up);
    const Edge edge = next_edge(&bulk);
    EXPECT_EQ(edge.offset, step.line);
    EXPECT_EQ(edge.type, step.up ? GPIOD_LINE_EVENT_RISING_EDGE : GPIOD_LINE_EVENT_FALLING_EDGE);
    // Kernel timestamps on CLOCK_MONOTONIC, strictly in the order the edges happened.
    EXPECT_GT(edge.ns, previous);
    EXPECT_LE(edge.ns, monotonic_ns());
    previous = edge.ns;
    EXPECT_EQ(gpiod_line_get_value(gpiod_line_bulk_get_line(&bulk, step.line)), step.up);
  }
  // No edge for a pull that does not change the level.
  sim.set_pull(0, false);
  const timespec short_wait{0, 200'000'000};
  EXPECT_EQ(gpiod_line_event_wait_bulk(&bulk, &short_wait, nullptr), 0);
  gpiod_line_release_bulk(&bulk);
}

TEST(GpioSim, OutputLineDrivenByConsumerIsSeenBySimulator) {
  GpioSimChip sim(1);
  ChipPtr chip(gpiod_chip_open(sim.dev_path().c_str()), &gpiod_chip_close);
  ASSERT_NE(chip, nullptr);
  gpiod_line* line = gpiod_chip_get_line(chip.get(), 0);
  ASSERT_NE(line, nullptr);
  ASSERT_EQ(gpiod_line_request_output(line, "hapticd-direction", 1), 0);
  EXPECT_TRUE(sim.value(0));
  ASSERT_EQ(gpiod_line_set_value(line, 0), 0);
  EXPECT_FALSE(sim.value(0));
  gpiod_line_release(line);
}

}  // namespace
}  // namespace hapticd::kernel_test
