// libgpiod 2.x (Debian 13), the kernel's GPIO uAPI v2: one line request holds every line of the
// chip (each joint's inputs with both-edge detection on the monotonic clock, each joint's
// direction output), its events
// come from one descriptor through a preallocated edge-event buffer, and each event carries
// a global sequence number, given in the interrupt's hard part: a gap means the kernel's
// buffer overflowed (it drops the oldest) or an edge was merged into the next on its line, and
// tells how many edges were lost.
#include <dirent.h>
#include <gpiod.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "drivers/device.h"
#include "drivers/gpio/gpio_transport.h"
#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/gpiod_lines.h"
#include "drivers/gpio/gpiod_lines_common.h"

namespace hapticd::drivers::gpio {
namespace {

using gpiod_common::InputLine;
using gpiod_common::kConsumer;
using gpiod_common::why;

constexpr std::size_t kEventBuffer = 256;  // the kernel's and ours: many ticks of edges

// gpiochip paths to try for `chip`: a path as given, a name under /dev, else every chip
// (matched by label once open).
gpiod_chip* open_chip(const std::string& chip, std::string& desc) {
  const auto describe = [&](gpiod_chip* c) {
    gpiod_chip_info* info = gpiod_chip_get_info(c);
    if (info == nullptr) return false;
    const bool match =
        chip == gpiod_chip_info_get_label(info) || chip == gpiod_chip_info_get_name(info);
    desc =
        std::string(gpiod_chip_info_get_name(info)) + " [" + gpiod_chip_info_get_label(info) + "]";
    gpiod_chip_info_free(info);
    return match;
  };
  if (chip.find('/') != std::string::npos || chip.rfind("gpiochip", 0) == 0) {
    const std::string path = chip.front() == '/' ? chip : "/dev/" + chip;
    gpiod_chip* c = gpiod_chip_open(path.c_str());
    if (c != nullptr) describe(c);
    return c;
  }
  DIR* dev = opendir("/dev");
  if (dev == nullptr) return nullptr;
  gpiod_chip* found = nullptr;
  while (dirent* e = readdir(dev)) {
    const std::string path = std::string("/dev/") + e->d_name;
    if (std::strncmp(e->d_name, "gpiochip", 8) != 0 || !gpiod_is_gpiochip_device(path.c_str())) {
      continue;
    }
    gpiod_chip* c = gpiod_chip_open(path.c_str());
    if (c == nullptr) continue;
    if (describe(c)) {
      found = c;
      break;
    }
    gpiod_chip_close(c);
  }
  closedir(dev);
  if (found == nullptr) errno = ENOENT;
  return found;
}

// One request of `inputs` (both edges, monotonic timestamps) and each joint's direction output
// at its starting level; null with `err` set when the kernel or the library refuses.
gpiod_line_request* request_lines(gpiod_chip* chip, const std::vector<unsigned>& inputs,
                                  std::span<const LineOffsets> joints, int& err) {
  gpiod_line_request* request = nullptr;
  gpiod_line_settings* in = gpiod_line_settings_new();
  gpiod_line_settings* out[2] = {gpiod_line_settings_new(), gpiod_line_settings_new()};
  gpiod_line_config* lc = gpiod_line_config_new();
  gpiod_request_config* rc = gpiod_request_config_new();
  err = ENOMEM;
  if (in != nullptr && out[0] != nullptr && out[1] != nullptr && lc != nullptr && rc != nullptr) {
    gpiod_line_settings_set_direction(in, GPIOD_LINE_DIRECTION_INPUT);
    gpiod_line_settings_set_edge_detection(in, GPIOD_LINE_EDGE_BOTH);
    gpiod_line_settings_set_event_clock(in, GPIOD_LINE_CLOCK_MONOTONIC);
    // out[level]: a direction output starting at that level.
    for (int level = 0; level < 2; ++level) {
      gpiod_line_settings_set_direction(out[level], GPIOD_LINE_DIRECTION_OUTPUT);
      gpiod_line_settings_set_output_value(
          out[level], level != 0 ? GPIOD_LINE_VALUE_ACTIVE : GPIOD_LINE_VALUE_INACTIVE);
    }
    gpiod_request_config_set_consumer(rc, kConsumer);
    gpiod_request_config_set_event_buffer_size(rc, kEventBuffer);
    bool added = gpiod_line_config_add_line_settings(lc, inputs.data(), inputs.size(), in) == 0;
    for (const LineOffsets& j : joints) {
      added = added && gpiod_line_config_add_line_settings(lc, &j.direction, 1,
                                                           out[j.direction_level ? 1 : 0]) == 0;
    }
    if (added) request = gpiod_chip_request_lines(chip, rc, lc);
    err = errno;
  }
  gpiod_request_config_free(rc);
  gpiod_line_config_free(lc);
  gpiod_line_settings_free(out[1]);
  gpiod_line_settings_free(out[0]);
  gpiod_line_settings_free(in);
  return request;
}

}  // namespace

struct GpiodLines::Impl {
  gpiod_chip* chip = nullptr;
  gpiod_line_request* request = nullptr;
  gpiod_edge_event_buffer* buffer = nullptr;
  std::string chip_desc;
  std::vector<InputLine> inputs;  // fixed after open
  std::vector<gpiod_common::DirectionLine> directions;
  SequenceCheck seq;

  const InputLine& input_of(unsigned offset) const noexcept {
    for (const InputLine& in : inputs) {
      if (in.offset == offset) return in;
    }
    return inputs.back();  // not requested: cannot happen
  }
};

GpiodLines::GpiodLines() : impl_(std::make_unique<Impl>()) {}
GpiodLines::~GpiodLines() { close(); }

std::string GpiodLines::api() {
  return std::string("libgpiod ") + gpiod_api_version() + " (API 2)";
}

void GpiodLines::open(const std::string& chip, std::span<const LineOffsets> joints) {
  close();
  Impl& m = *impl_;
  m.chip = open_chip(chip, m.chip_desc);
  if (m.chip == nullptr) {
    throw DeviceError("gpio: cannot open GPIO chip '" + chip + "': " + why(errno));
  }
  m.inputs = gpiod_common::input_lines(joints);
  m.directions.clear();
  std::vector<unsigned> offsets;
  for (const InputLine& in : m.inputs) offsets.push_back(in.offset);
  std::string direction_offsets;
  for (const LineOffsets& j : joints) {
    m.directions.push_back({j.joint, j.direction});
    direction_offsets += (direction_offsets.empty() ? "" : ", ") + std::to_string(j.direction);
  }

  int err = ENOMEM;
  m.request = request_lines(m.chip, offsets, joints, err);
  if (m.request == nullptr) {
    close();
    throw DeviceError("gpio: cannot request lines of " + chip + " (encoder, direction " +
                      direction_offsets + "): " + why(err));
  }
  m.buffer = gpiod_edge_event_buffer_new(kEventBuffer);
  const int e = m.buffer == nullptr
                    ? errno
                    : gpiod_common::make_nonblocking(gpiod_line_request_get_fd(m.request));
  if (m.buffer == nullptr || e != 0) {
    close();
    throw DeviceError("gpio: cannot set up the edge-event descriptor: " + why(e));
  }
  m.seq.reset();
}

void GpiodLines::close() noexcept {
  Impl& m = *impl_;
  if (m.buffer != nullptr) gpiod_edge_event_buffer_free(m.buffer);
  if (m.request != nullptr) gpiod_line_request_release(m.request);
  if (m.chip != nullptr) gpiod_chip_close(m.chip);
  m.buffer = nullptr;
  m.request = nullptr;
  m.chip = nullptr;
}

void GpiodLines::read_levels(std::span<std::uint8_t> levels) {
  gpiod_common::read_levels(
      impl_->inputs,
      [&](std::size_t i) {
        switch (gpiod_line_request_get_value(impl_->request, impl_->inputs[i].offset)) {
          case GPIOD_LINE_VALUE_ERROR:
            return -1;
          case GPIOD_LINE_VALUE_ACTIVE:
            return 1;
          default:
            return 0;
        }
      },
      levels);
}

std::string GpiodLines::describe() const {
  return gpiod_common::describe(impl_->chip_desc, impl_->inputs, impl_->directions);
}

// RT-safe: called every tick.
int GpiodLines::read_events(std::span<Edge> out, std::size_t& count,
                            std::span<std::uint64_t> lost) noexcept {
  Impl& m = *impl_;
  count = 0;
  if (m.request == nullptr) return EBADF;
  while (count < out.size()) {
    const std::size_t want = std::min(out.size() - count, kEventBuffer);
    const int n = gpiod_line_request_read_edge_events(m.request, m.buffer, want);
    if (n < 0) {
      if (errno == EAGAIN) break;
      return errno;
    }
    for (int i = 0; i < n; ++i) {
      gpiod_edge_event* ev =
          gpiod_edge_event_buffer_get_event(m.buffer, static_cast<unsigned long>(i));
      Edge& e = out[count++];
      e.time_ns = static_cast<std::int64_t>(gpiod_edge_event_get_timestamp_ns(ev));
      e.seqno = static_cast<std::uint32_t>(gpiod_edge_event_get_global_seqno(ev));
      const InputLine& in = m.input_of(gpiod_edge_event_get_line_offset(ev));
      e.line = in.role;
      e.joint = in.joint;
      e.level = gpiod_edge_event_get_event_type(ev) == GPIOD_EDGE_EVENT_RISING_EDGE;
    }
    if (static_cast<std::size_t>(n) < want) break;
  }
  // Each line's interrupt thread queues its own events, so two lines' edges close together
  // can come out of the order the kernel numbered them in: back in that order (as uAPI v1's
  // lines are merged by timestamp), or each such pair would count as edges lost and out of
  // order. Wrap-aware.
  gpiod_common::order_edges(out.first(count), [](const Edge& a, const Edge& b) {
    return static_cast<std::int32_t>(b.seqno - a.seqno) > 0;
  });
  // The kernel numbers events 1, 2, 3... per request: a gap is some joint's on this chip.
  std::uint64_t gap = 0;
  for (std::size_t i = 0; i < count; ++i) gap += m.seq.next(out[i].seqno);
  if (gap != 0) {
    for (const gpiod_common::DirectionLine& d : m.directions) lost[d.joint] += gap;
  }
  return 0;
}

// RT-safe: called every tick the direction changes.
int GpiodLines::set_direction(std::uint8_t joint, bool level) noexcept {
  const Impl& m = *impl_;
  if (m.request == nullptr) return EBADF;
  for (const gpiod_common::DirectionLine& d : m.directions) {
    if (d.joint != joint) continue;
    return gpiod_line_request_set_value(
               m.request, d.offset, level ? GPIOD_LINE_VALUE_ACTIVE : GPIOD_LINE_VALUE_INACTIVE) ==
                   0
               ? 0
               : errno;
  }
  return EBADF;
}

}  // namespace hapticd::drivers::gpio
