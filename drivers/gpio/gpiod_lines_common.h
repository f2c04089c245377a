// What the two libgpiod back-ends (gpiod_lines_v1.cpp for libgpiod 1.6, gpiod_lines_v2.cpp for
// 2.x; gpiod_lines.h) share, apart from the library calls that differ entirely between the
// two APIs: the consumer name, the input lines a LineOffsets asks for, errno in words, the
// non-blocking event descriptor, the levels read line by line, the description, and the
// ordering of the edges read in one tick. No <gpiod.h> here.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "drivers/gpio/gpiod_lines.h"

namespace hapticd::drivers::gpio::gpiod_common {

inline constexpr const char* kConsumer = "hapticd";

struct InputLine {
  Line role = Line::kA;
  unsigned offset = 0;
  std::uint8_t joint = 0;
};

// A joint's direction output.
struct DirectionLine {
  std::uint8_t joint = 0;
  unsigned offset = 0;
};

// The input lines `joints` ask for: each joint's A, B, then its index and fault line where set.
std::vector<InputLine> input_lines(std::span<const LineOffsets> joints);

// errno in words, with what to do about the two a person meets: a line another process or
// driver holds, and a chip the user may not open.
std::string why(int err);

// 0 or errno. The library reads its event descriptor with a blocking read(2); non-blocking, an
// empty kernel FIFO reads as EAGAIN, so the RT thread never waits in it.
int make_nonblocking(int fd) noexcept;

// Not RT-safe. Raw levels (wire::kLevel* bits) of `inputs` into levels[joint], input i read by
// `value(i)`: 1, 0, or -1 with errno set, which throws DeviceError naming the line.
void read_levels(std::span<const InputLine> inputs, const std::function<int(std::size_t)>& value,
                 std::span<std::uint8_t> levels);

// "gpiochip1 [gpio-sim.0] lines 0,1,dir 2"; with several joints on the chip each joint's
// lines, "; " between them.
std::string describe(const std::string& chip, std::span<const InputLine> inputs,
                     std::span<const DirectionLine> directions);

// RT-safe: called every tick. Puts the edges read in one tick back in the order the kernel
// saw them, `before(a, b)` saying a came first: insertion sort, stable, for the handful of
// edges a tick reads.
template <typename Before>
void order_edges(std::span<Edge> edges, Before before) noexcept {
  for (std::size_t i = 1; i < edges.size(); ++i) {
    const Edge e = edges[i];
    std::size_t j = i;
    for (; j > 0 && before(e, edges[j - 1]); --j) edges[j] = edges[j - 1];
    edges[j] = e;
  }
}

}  // namespace hapticd::drivers::gpio::gpiod_common
