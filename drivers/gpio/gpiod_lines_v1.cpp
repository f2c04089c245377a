// libgpiod 1.6 (Debian 12), the kernel's GPIO uAPI v1: each input line requested for both-edge
// events has its own event descriptor and its own 16-event kernel FIFO; an overflow drops the
// newest events silently (no sequence numbers), so lost edges show only as the decoder's
// illegal transitions. Event timestamps are CLOCK_MONOTONIC (Linux >= 5.7).
#include <fcntl.h>
#include <gpiod.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <vector>

#include "drivers/device.h"
#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/gpiod_lines.h"

namespace hapticd::drivers::gpio {
namespace {

constexpr const char* kConsumer = "hapticd";
constexpr unsigned kKernelFifo = 16;  // uAPI v1: events a line's FIFO holds

std::string why(int err) {
  if (err == EBUSY) return "busy (another process or a kernel driver holds it: see gpioinfo)";
  if (err == EACCES || err == EPERM) {
    return std::string(std::strerror(err)) +
           " (`hapticd udev-rules` writes the rules that give group hapticd access)";
  }
  return std::strerror(err);
}

}  // namespace

struct GpiodLines::Impl {
  gpiod_chip* chip = nullptr;
  std::string chip_desc;
  struct Input {
    gpiod_line* line = nullptr;
    Line role = Line::kA;
    unsigned offset = 0;
    int fd = -1;
  };
  std::vector<Input> inputs;  // fixed after open: the RT path only indexes it
  gpiod_line* direction = nullptr;
  unsigned direction_offset = 0;

  void request_input(Line role, unsigned offset) {
    gpiod_line* l = gpiod_chip_get_line(chip, offset);
    if (l == nullptr) {
      throw DeviceError("gpio: " + chip_desc + " has no line " + std::to_string(offset));
    }
    if (gpiod_line_request_both_edges_events(l, kConsumer) != 0) {
      throw DeviceError("gpio: cannot request line " + std::to_string(offset) + " of " + chip_desc +
                        " for edge events: " + why(errno));
    }
    const int fd = gpiod_line_event_get_fd(l);
    // The library reads with a blocking read(2); non-blocking makes an empty FIFO EAGAIN.
    const int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) != 0) {
      const int e = errno;
      gpiod_line_release(l);
      throw DeviceError("gpio: cannot make line " + std::to_string(offset) +
                        "'s event descriptor non-blocking: " + why(e));
    }
    inputs.push_back({l, role, offset, fd});
  }
};

GpiodLines::GpiodLines() : impl_(std::make_unique<Impl>()) {}
GpiodLines::~GpiodLines() { close(); }

std::string GpiodLines::api() {
  return std::string("libgpiod ") + gpiod_version_string() + " (API 1)";
}

void GpiodLines::open(const std::string& chip, const LineOffsets& lines, bool direction_level) {
  close();
  Impl& m = *impl_;
  // Path, name, number or label: the library's own lookup.
  m.chip = gpiod_chip_open_lookup(chip.c_str());
  if (m.chip == nullptr) {
    throw DeviceError("gpio: cannot open GPIO chip '" + chip + "': " + why(errno));
  }
  m.chip_desc = std::string(gpiod_chip_name(m.chip)) + " [" + gpiod_chip_label(m.chip) + "]";
  try {
    m.inputs.reserve(4);
    m.request_input(Line::kA, lines.a);
    m.request_input(Line::kB, lines.b);
    if (lines.index) m.request_input(Line::kIndex, *lines.index);
    if (lines.fault) m.request_input(Line::kFault, *lines.fault);
    m.direction = gpiod_chip_get_line(m.chip, lines.direction);
    if (m.direction == nullptr ||
        gpiod_line_request_output(m.direction, kConsumer, direction_level ? 1 : 0) != 0) {
      const int e = errno;
      m.direction = nullptr;
      throw DeviceError("gpio: cannot request line " + std::to_string(lines.direction) + " of " +
                        m.chip_desc + " as the direction output: " + why(e));
    }
    m.direction_offset = lines.direction;
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
  m.direction = nullptr;
}

std::uint8_t GpiodLines::read_levels() {
  std::uint8_t levels = 0;
  for (const Impl::Input& in : impl_->inputs) {
    const int v = gpiod_line_get_value(in.line);
    if (v < 0) {
      throw DeviceError("gpio: cannot read line " + std::to_string(in.offset) + ": " + why(errno));
    }
    if (v != 0) levels |= static_cast<std::uint8_t>(1u << static_cast<unsigned>(in.role));
  }
  return levels;
}

std::string GpiodLines::describe() const {
  std::string lines;
  for (const Impl::Input& in : impl_->inputs) lines += std::to_string(in.offset) + ",";
  return impl_->chip_desc + " lines " + lines + "dir " + std::to_string(impl_->direction_offset);
}

// RT-safe: called every tick.
int GpiodLines::read_events(std::span<Edge> out, std::size_t& count, std::uint64_t& lost) noexcept {
  count = 0;
  lost = 0;  // uAPI v1 drops the newest events without a trace
  std::array<gpiod_line_event, kKernelFifo> ev;
  for (const Impl::Input& in : impl_->inputs) {
    while (count < out.size()) {
      const unsigned room =
          static_cast<unsigned>(std::min<std::size_t>(kKernelFifo, out.size() - count));
      const int n = gpiod_line_event_read_fd_multiple(in.fd, ev.data(), room);
      if (n < 0) {
        if (errno == EAGAIN) break;
        return errno;
      }
      for (int i = 0; i < n; ++i) {
        Edge& e = out[count++];
        e.time_ns = static_cast<std::int64_t>(ev[i].ts.tv_sec) * 1'000'000'000 + ev[i].ts.tv_nsec;
        e.seqno = 0;
        e.line = in.role;
        e.level = ev[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE;
      }
      if (static_cast<unsigned>(n) < room) break;
    }
  }
  // Each line's events are in time order; merge the lines by timestamp (insertion sort,
  // stable: a handful of events per tick).
  for (std::size_t i = 1; i < count; ++i) {
    const Edge e = out[i];
    std::size_t j = i;
    for (; j > 0 && out[j - 1].time_ns > e.time_ns; --j) out[j] = out[j - 1];
    out[j] = e;
  }
  return 0;
}

// RT-safe: called every tick the direction changes.
int GpiodLines::set_direction(bool level) noexcept {
  if (impl_->direction == nullptr) return EBADF;
  return gpiod_line_set_value(impl_->direction, level ? 1 : 0) == 0 ? 0 : errno;
}

}  // namespace hapticd::drivers::gpio
