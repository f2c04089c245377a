// libgpiod 1.6 (Debian 12), the kernel's GPIO uAPI v1: each input line requested for both-edge
// events has its own event descriptor and its own 16-event kernel FIFO (so a tick reads each
// input line of each joint on the chip once); an overflow drops the newest events silently (no
// sequence numbers), so lost edges show only as the decoder's illegal transitions. Event
// timestamps are CLOCK_MONOTONIC (Linux >= 5.7).
#include <gpiod.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <vector>

#include "drivers/device.h"
#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/gpiod_lines.h"
#include "drivers/gpio/gpiod_lines_common.h"

namespace hapticd::drivers::gpio {
namespace {

using gpiod_common::InputLine;
using gpiod_common::kConsumer;
using gpiod_common::why;

constexpr unsigned kKernelFifo = 16;  // uAPI v1: events a line's FIFO holds

}  // namespace

struct GpiodLines::Impl {
  gpiod_chip* chip = nullptr;
  std::string chip_desc;
  // Index-aligned and fixed after open: the RT path only indexes them.
  std::vector<InputLine> inputs;
  std::vector<gpiod_line*> lines;
  std::vector<int> fds;  // each input line's own event descriptor
  std::vector<gpiod_common::DirectionLine> directions;
  std::vector<gpiod_line*> direction_lines;  // index-aligned with directions

  void request_direction(const LineOffsets& j) {
    gpiod_line* l = gpiod_chip_get_line(chip, j.direction);
    if (l == nullptr || gpiod_line_request_output(l, kConsumer, j.direction_level ? 1 : 0) != 0) {
      const int e = errno;
      throw DeviceError("gpio: cannot request line " + std::to_string(j.direction) + " of " +
                        chip_desc + " as the direction output: " + why(e));
    }
    directions.push_back({j.joint, j.direction});
    direction_lines.push_back(l);
  }

  void request_input(const InputLine& in) {
    gpiod_line* l = gpiod_chip_get_line(chip, in.offset);
    if (l == nullptr) {
      throw DeviceError("gpio: " + chip_desc + " has no line " + std::to_string(in.offset));
    }
    if (gpiod_line_request_both_edges_events(l, kConsumer) != 0) {
      throw DeviceError("gpio: cannot request line " + std::to_string(in.offset) + " of " +
                        chip_desc + " for edge events: " + why(errno));
    }
    const int fd = gpiod_line_event_get_fd(l);
    if (const int e = gpiod_common::make_nonblocking(fd); e != 0) {
      gpiod_line_release(l);
      throw DeviceError("gpio: cannot make line " + std::to_string(in.offset) +
                        "'s event descriptor non-blocking: " + why(e));
    }
    inputs.push_back(in);
    lines.push_back(l);
    fds.push_back(fd);
  }
};

GpiodLines::GpiodLines() : impl_(std::make_unique<Impl>()) {}
GpiodLines::~GpiodLines() { close(); }

std::string GpiodLines::api() {
  return std::string("libgpiod ") + gpiod_version_string() + " (API 1)";
}

void GpiodLines::open(const std::string& chip, std::span<const LineOffsets> joints) {
  close();
  Impl& m = *impl_;
  // Path, name, number or label: the library's own lookup.
  m.chip = gpiod_chip_open_lookup(chip.c_str());
  if (m.chip == nullptr) {
    throw DeviceError("gpio: cannot open GPIO chip '" + chip + "': " + why(errno));
  }
  m.chip_desc = std::string(gpiod_chip_name(m.chip)) + " [" + gpiod_chip_label(m.chip) + "]";
  try {
    for (const InputLine& in : gpiod_common::input_lines(joints)) m.request_input(in);
    for (const LineOffsets& j : joints) m.request_direction(j);
  } catch (...) {
    close();
    throw;
  }
}

void GpiodLines::close() noexcept {
  Impl& m = *impl_;
  if (m.chip == nullptr) return;
  // Closing the chip releases every line it handed out.
  gpiod_chip_close(m.chip);
  m.chip = nullptr;
  m.inputs.clear();
  m.lines.clear();
  m.fds.clear();
  m.directions.clear();
  m.direction_lines.clear();
}

void GpiodLines::read_levels(std::span<std::uint8_t> levels) {
  gpiod_common::read_levels(
      impl_->inputs, [&](std::size_t i) { return gpiod_line_get_value(impl_->lines[i]); }, levels);
}

std::string GpiodLines::describe() const {
  return gpiod_common::describe(impl_->chip_desc, impl_->inputs, impl_->directions);
}

// RT-safe: called every tick.
int GpiodLines::read_events(std::span<Edge> out, std::size_t& count,
                            std::span<std::uint64_t> lost) noexcept {
  count = 0;
  (void)lost;  // uAPI v1 drops the newest events without a trace
  std::array<gpiod_line_event, kKernelFifo> ev;
  const Impl& m = *impl_;
  for (std::size_t line = 0; line < m.inputs.size(); ++line) {
    while (count < out.size()) {
      const unsigned room =
          static_cast<unsigned>(std::min<std::size_t>(kKernelFifo, out.size() - count));
      const int n = gpiod_line_event_read_fd_multiple(m.fds[line], ev.data(), room);
      if (n < 0) {
        if (errno == EAGAIN) break;
        return errno;
      }
      for (int i = 0; i < n; ++i) {
        Edge& e = out[count++];
        e.time_ns = static_cast<std::int64_t>(ev[i].ts.tv_sec) * 1'000'000'000 + ev[i].ts.tv_nsec;
        e.seqno = 0;
        e.line = m.inputs[line].role;
        e.joint = m.inputs[line].joint;
        e.level = ev[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE;
      }
      if (static_cast<unsigned>(n) < room) break;
    }
  }
  // Each line's events are in time order; the lines merged by timestamp (each joint's edges
  // then in their order, which is all its decoder needs).
  gpiod_common::order_edges(out.first(count),
                            [](const Edge& a, const Edge& b) { return a.time_ns < b.time_ns; });
  return 0;
}

// RT-safe: called every tick the direction changes.
int GpiodLines::set_direction(std::uint8_t joint, bool level) noexcept {
  const Impl& m = *impl_;
  for (std::size_t d = 0; d < m.directions.size(); ++d) {
    if (m.directions[d].joint != joint) continue;
    return gpiod_line_set_value(m.direction_lines[d], level ? 1 : 0) == 0 ? 0 : errno;
  }
  return EBADF;
}

}  // namespace hapticd::drivers::gpio
