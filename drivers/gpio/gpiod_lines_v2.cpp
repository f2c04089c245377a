// libgpiod 2.x (Debian 13), the kernel's GPIO uAPI v2: one line request holds every line (the
// inputs with both-edge detection on the monotonic clock, the direction output), its events
// come from one descriptor through a preallocated edge-event buffer, and each event carries
// a global sequence number, given in the interrupt's hard part: a gap means the kernel's
// buffer overflowed (it drops the oldest) or an edge was merged into the next on its line, and
// tells how many edges were lost.
#include <dirent.h>
#include <fcntl.h>
#include <gpiod.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "drivers/device.h"
#include "drivers/gpio/gpio_transport.h"
#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/gpiod_lines.h"

namespace hapticd::drivers::gpio {
namespace {

constexpr const char* kConsumer = "hapticd";
constexpr std::size_t kEventBuffer = 256;  // the kernel's and ours: many ticks of edges

std::string why(int err) {
  if (err == EBUSY) return "busy (another process or a kernel driver holds it: see gpioinfo)";
  if (err == EACCES || err == EPERM) {
    return std::string(std::strerror(err)) +
           " (`hapticd udev-rules` writes the rules that give group hapticd access)";
  }
  return std::strerror(err);
}

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

}  // namespace

struct GpiodLines::Impl {
  gpiod_chip* chip = nullptr;
  gpiod_line_request* request = nullptr;
  gpiod_edge_event_buffer* buffer = nullptr;
  std::string chip_desc;
  struct Input {
    Line role;
    unsigned offset;
  };
  std::vector<Input> inputs;  // fixed after open
  unsigned direction = 0;
  SequenceCheck seq;

  Line role_of(unsigned offset) const noexcept {
    for (const Input& in : inputs) {
      if (in.offset == offset) return in.role;
    }
    return Line::kFault;  // not requested: cannot happen
  }
};

GpiodLines::GpiodLines() : impl_(std::make_unique<Impl>()) {}
GpiodLines::~GpiodLines() { close(); }

std::string GpiodLines::api() {
  return std::string("libgpiod ") + gpiod_api_version() + " (API 2)";
}

void GpiodLines::open(const std::string& chip, const LineOffsets& lines, bool direction_level) {
  close();
  Impl& m = *impl_;
  m.chip = open_chip(chip, m.chip_desc);
  if (m.chip == nullptr) {
    throw DeviceError("gpio: cannot open GPIO chip '" + chip + "': " + why(errno));
  }
  m.inputs = {{Line::kA, lines.a}, {Line::kB, lines.b}};
  if (lines.index) m.inputs.push_back({Line::kIndex, *lines.index});
  if (lines.fault) m.inputs.push_back({Line::kFault, *lines.fault});
  m.direction = lines.direction;
  std::vector<unsigned> offsets;
  for (const Impl::Input& in : m.inputs) offsets.push_back(in.offset);

  gpiod_line_settings* in = gpiod_line_settings_new();
  gpiod_line_settings* out = gpiod_line_settings_new();
  gpiod_line_config* lc = gpiod_line_config_new();
  gpiod_request_config* rc = gpiod_request_config_new();
  int err = ENOMEM;
  if (in != nullptr && out != nullptr && lc != nullptr && rc != nullptr) {
    gpiod_line_settings_set_direction(in, GPIOD_LINE_DIRECTION_INPUT);
    gpiod_line_settings_set_edge_detection(in, GPIOD_LINE_EDGE_BOTH);
    gpiod_line_settings_set_event_clock(in, GPIOD_LINE_CLOCK_MONOTONIC);
    gpiod_line_settings_set_direction(out, GPIOD_LINE_DIRECTION_OUTPUT);
    gpiod_line_settings_set_output_value(
        out, direction_level ? GPIOD_LINE_VALUE_ACTIVE : GPIOD_LINE_VALUE_INACTIVE);
    gpiod_request_config_set_consumer(rc, kConsumer);
    gpiod_request_config_set_event_buffer_size(rc, kEventBuffer);
    if (gpiod_line_config_add_line_settings(lc, offsets.data(), offsets.size(), in) == 0 &&
        gpiod_line_config_add_line_settings(lc, &m.direction, 1, out) == 0) {
      m.request = gpiod_chip_request_lines(m.chip, rc, lc);
    }
    err = errno;
  }
  gpiod_request_config_free(rc);
  gpiod_line_config_free(lc);
  gpiod_line_settings_free(out);
  gpiod_line_settings_free(in);
  if (m.request == nullptr) {
    close();
    throw DeviceError("gpio: cannot request lines of " + chip + " (encoder, direction " +
                      std::to_string(lines.direction) + "): " + why(err));
  }
  // The library reads with a blocking read(2); non-blocking makes an empty buffer EAGAIN.
  const int fd = gpiod_line_request_get_fd(m.request);
  const int flags = fcntl(fd, F_GETFL);
  m.buffer = gpiod_edge_event_buffer_new(kEventBuffer);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) != 0 || m.buffer == nullptr) {
    const int e = errno;
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

std::uint8_t GpiodLines::read_levels() {
  std::uint8_t levels = 0;
  for (const Impl::Input& in : impl_->inputs) {
    const gpiod_line_value v = gpiod_line_request_get_value(impl_->request, in.offset);
    if (v == GPIOD_LINE_VALUE_ERROR) {
      throw DeviceError("gpio: cannot read line " + std::to_string(in.offset) + ": " + why(errno));
    }
    if (v == GPIOD_LINE_VALUE_ACTIVE) {
      levels |= static_cast<std::uint8_t>(1u << static_cast<unsigned>(in.role));
    }
  }
  return levels;
}

std::string GpiodLines::describe() const {
  std::string lines;
  for (const Impl::Input& in : impl_->inputs) lines += std::to_string(in.offset) + ",";
  return impl_->chip_desc + " lines " + lines + "dir " + std::to_string(impl_->direction);
}

// RT-safe: called every tick.
int GpiodLines::read_events(std::span<Edge> out, std::size_t& count, std::uint64_t& lost) noexcept {
  Impl& m = *impl_;
  count = 0;
  lost = 0;
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
      e.line = m.role_of(gpiod_edge_event_get_line_offset(ev));
      e.level = gpiod_edge_event_get_event_type(ev) == GPIOD_EDGE_EVENT_RISING_EDGE;
    }
    if (static_cast<std::size_t>(n) < want) break;
  }
  // Each line's interrupt thread queues its own events, so two lines' edges close together
  // can come out of the order the kernel numbered them in: back in that order (as uAPI v1's
  // lines are merged by timestamp), or each such pair would count as edges lost and out of
  // order. Insertion sort, wrap-aware: a handful of events per tick.
  for (std::size_t i = 1; i < count; ++i) {
    const Edge e = out[i];
    std::size_t j = i;
    for (; j > 0 && static_cast<std::int32_t>(out[j - 1].seqno - e.seqno) > 0; --j) {
      out[j] = out[j - 1];
    }
    out[j] = e;
  }
  // The kernel numbers events 1, 2, 3... per request.
  for (std::size_t i = 0; i < count; ++i) lost += m.seq.next(out[i].seqno);
  return 0;
}

// RT-safe: called every tick the direction changes.
int GpiodLines::set_direction(bool level) noexcept {
  if (impl_->request == nullptr) return EBADF;
  return gpiod_line_request_set_value(
             impl_->request, impl_->direction,
             level ? GPIOD_LINE_VALUE_ACTIVE : GPIOD_LINE_VALUE_INACTIVE) == 0
             ? 0
             : errno;
}

}  // namespace hapticd::drivers::gpio
