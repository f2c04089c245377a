#include "drivers/evdev/libevdev_transport.h"

#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <ctime>
#include <filesystem>
#include <system_error>

#include "base/errno_text.h"
#include "drivers/device.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::evdev {

// The codec restates the kernel's numbers (it includes no OS header): they must be these.
static_assert(kEvSyn == EV_SYN && kEvAbs == EV_ABS && kEvFf == EV_FF &&
              kEvFfStatus == EV_FF_STATUS);
static_assert(kSynReport == SYN_REPORT && kSynDropped == SYN_DROPPED);
static_assert(kFfConstant == FF_CONSTANT && kFfGain == FF_GAIN && kFfAutocenter == FF_AUTOCENTER);
static_assert(kFfStatusStopped == FF_STATUS_STOPPED && kFfStatusPlaying == FF_STATUS_PLAYING);
static_assert(kAbsMax == ABS_MAX);

namespace {

namespace fs = std::filesystem;

struct EvdevFree {
  void operator()(libevdev* d) const noexcept { libevdev_free(d); }
};
using EvdevPtr = std::unique_ptr<libevdev, EvdevFree>;

// libevdev reports what it finds wrong through a log function; on the RT thread nothing may
// print, so its messages are only counted (a bug in the device, a reader not keeping up) and
// the count published as the driver's library_messages.
void count_message(const libevdev*, enum libevdev_log_priority, void* data, const char*, int,
                   const char*, const char*, va_list) {
  static_cast<std::atomic<std::uint64_t>*>(data)->fetch_add(1, std::memory_order_relaxed);
}

// The driver bound to the device behind the input device: its nearest ancestor in sysfs that
// has one (a HID device's is two levels up, past the input class directory).
std::string sysfs_driver(const std::string& event) {
  std::error_code ec;
  fs::path dir = fs::canonical("/sys/class/input/" + event + "/device", ec);
  for (int up = 0; !ec && up < 4 && dir.has_parent_path(); ++up, dir = dir.parent_path()) {
    const fs::path driver = fs::read_symlink(dir / "driver", ec);
    if (!ec) return driver.filename().string();
    ec.clear();
  }
  return {};
}

bool sysfs_virtual(const std::string& event) {
  std::error_code ec;
  const fs::path input = fs::canonical("/sys/class/input/" + event + "/device", ec);
  return !ec && input.string().find("/devices/virtual/") != std::string::npos;
}

InputListing describe_device(const std::string& path, libevdev* d, int fd) {
  InputListing l;
  l.path = path;
  l.name = libevdev_get_name(d) ? libevdev_get_name(d) : "";
  l.phys = libevdev_get_phys(d) ? libevdev_get_phys(d) : "";
  l.uniq = libevdev_get_uniq(d) ? libevdev_get_uniq(d) : "";
  l.bus = static_cast<std::uint16_t>(libevdev_get_id_bustype(d));
  l.vendor_id = static_cast<std::uint16_t>(libevdev_get_id_vendor(d));
  l.product_id = static_cast<std::uint16_t>(libevdev_get_id_product(d));
  l.ff_constant = libevdev_has_event_code(d, EV_FF, FF_CONSTANT);
  l.ff_gain = libevdev_has_event_code(d, EV_FF, FF_GAIN);
  l.ff_autocenter = libevdev_has_event_code(d, EV_FF, FF_AUTOCENTER);
  int effects = 0;
  if (l.ff_constant && ioctl(fd, EVIOCGEFFECTS, &effects) == 0) l.ff_effects = effects;
  for (int code = 0; code < ABS_MT_SLOT; ++code) {
    if (libevdev_has_event_code(d, EV_ABS, static_cast<unsigned>(code))) l.abs_axes.push_back(code);
  }
  const std::string event = fs::path(path).filename().string();
  l.kernel_driver = sysfs_driver(event);
  l.virtual_device = sysfs_virtual(event);
  return l;
}

void add_links(std::vector<InputListing>& all, const char* dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const fs::path target = fs::canonical(e.path(), ec);
    if (ec) continue;
    for (InputListing& l : all) {
      if (l.path == target.string()) l.links.push_back(e.path().string());
    }
  }
}

class LibevdevTransport final : public EvdevTransport {
 public:
  LibevdevTransport(io::UniqueFd fd, EvdevPtr dev, std::string path)
      : fd_(std::move(fd)), dev_(std::move(dev)), path_(std::move(path)) {
    libevdev_set_device_log_function(dev_.get(), count_message, LIBEVDEV_LOG_INFO, &messages_);
  }
  ~LibevdevTransport() override {
    emergency_ids_[0].store(-1);
    emergency_ids_[1].store(-1);
  }

  std::string describe() const override {
    return "evdev " + path_ + " \"" + std::string(libevdev_get_name(dev_.get())) + "\"";
  }

  wire::Facts facts(int code) override {
    wire::Facts f;
    libevdev* d = dev_.get();
    f.name = libevdev_get_name(d);
    f.phys = libevdev_get_phys(d) ? libevdev_get_phys(d) : "";
    f.uniq = libevdev_get_uniq(d) ? libevdev_get_uniq(d) : "";
    f.bus = static_cast<std::uint16_t>(libevdev_get_id_bustype(d));
    f.vendor = static_cast<std::uint16_t>(libevdev_get_id_vendor(d));
    f.product = static_cast<std::uint16_t>(libevdev_get_id_product(d));
    f.version = static_cast<std::uint16_t>(libevdev_get_id_version(d));
    f.has_axis = libevdev_has_event_code(d, EV_ABS, static_cast<unsigned>(code));
    if (f.has_axis) {
      input_absinfo abs{};  // the kernel's now, not libevdev's copy from when it was opened
      if (ioctl(fd_.get(), EVIOCGABS(code), &abs) != 0) throw failed("EVIOCGABS");
      f.range = {abs.minimum, abs.maximum, abs.resolution};
      f.value = abs.value;
      f.fuzz = abs.fuzz;
    }
    f.ff_constant = libevdev_has_event_code(d, EV_FF, FF_CONSTANT);
    f.ff_gain = libevdev_has_event_code(d, EV_FF, FF_GAIN);
    f.ff_autocenter = libevdev_has_event_code(d, EV_FF, FF_AUTOCENTER);
    int effects = 0;
    if (f.ff_constant && ioctl(fd_.get(), EVIOCGEFFECTS, &effects) != 0) {
      throw failed("EVIOCGEFFECTS");
    }
    f.ff_effects = effects;
    return f;
  }

  void set_fuzz(int code, int fuzz) override {
    input_absinfo abs{};
    if (ioctl(fd_.get(), EVIOCGABS(code), &abs) != 0) throw failed("EVIOCGABS");
    abs.fuzz = fuzz;
    if (const int rc = libevdev_kernel_set_abs_info(dev_.get(), static_cast<unsigned>(code), &abs);
        rc != 0) {
      errno = -rc;
      throw failed("EVIOCSABS");
    }
  }

  void grab(bool on) override {
    const int rc = libevdev_grab(dev_.get(), on ? LIBEVDEV_GRAB : LIBEVDEV_UNGRAB);
    if (rc == -EBUSY) {
      throw DeviceError("evdev: another process has grabbed " + path_ +
                        " (EVIOCGRAB: " + base::errno_text(EBUSY) + "); it must let go first");
    }
    if (rc < 0) throw DeviceError("evdev: EVIOCGRAB " + path_ + ": " + base::errno_text(-rc));
  }

  int upload(const wire::Effect& effect) override {
    ff_effect e = constant(effect);
    e.id = -1;
    if (ioctl(fd_.get(), EVIOCSFF, &e) != 0) throw failed("EVIOCSFF");
    return e.id;
  }

  int erase(int id) noexcept override { return ioctl(fd_.get(), EVIOCRMFF, id) == 0 ? 0 : errno; }

  // The update thread's: an ff_effect of its own on its stack.
  int update(const wire::Effect& effect) noexcept override {
    ff_effect e = constant(effect);
    return ioctl(fd_.get(), EVIOCSFF, &e) == 0 ? 0 : errno;
  }

  int write_ff(int code, int value) noexcept override {
    input_event ev{};
    ev.type = EV_FF;
    ev.code = static_cast<__u16>(code);
    ev.value = value;
    return ::write(fd_.get(), &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev) ? 0 : errno;
  }

  ReadStatus read(wire::Event& out, int& error) noexcept override {
    input_event ev{};
    while (true) {
      const unsigned flag = syncing_ ? LIBEVDEV_READ_FLAG_SYNC : LIBEVDEV_READ_FLAG_NORMAL;
      const int rc = libevdev_next_event(dev_.get(), flag, &ev);
      if (rc == -EAGAIN) {
        if (!syncing_) return ReadStatus::kEmpty;
        syncing_ = false;  // the resynchronisation is complete: back to the stream
        continue;
      }
      if (rc < 0) {
        error = -rc;
        return ReadStatus::kError;
      }
      out = {ev.type, ev.code, ev.value,
             static_cast<std::int64_t>(ev.input_event_sec) * 1'000'000'000 +
                 static_cast<std::int64_t>(ev.input_event_usec) * 1000};
      if (rc == LIBEVDEV_READ_STATUS_SYNC && !syncing_) {
        syncing_ = true;  // SYN_DROPPED: libevdev hands the kernel's state over next
        return ReadStatus::kDropped;
      }
      return ReadStatus::kEvent;
    }
  }

  std::uint64_t library_messages() const noexcept override {
    return messages_.load(std::memory_order_relaxed);
  }

  void set_emergency_effects(int first, int second) noexcept override {
    emergency_ids_[0].store(first);
    emergency_ids_[1].store(second);
  }

  void emergency() noexcept override {
    for (const std::atomic<int>& e : emergency_ids_) {
      const int id = e.load();
      if (id < 0) continue;
      input_event ev{};
      ev.type = EV_FF;
      ev.code = static_cast<__u16>(id);
      [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &ev, sizeof ev);
    }
  }

 private:
  DeviceError failed(const char* call) const {
    return DeviceError(std::string("evdev: ") + call + " on " + path_ + ": " +
                       base::errno_text(errno));
  }
  static ff_effect constant(const wire::Effect& e) noexcept {
    ff_effect out{};
    out.type = FF_CONSTANT;
    out.id = e.id;
    out.direction = e.direction;
    out.u.constant.level = e.level;
    out.replay.length = e.length_ms;
    out.replay.delay = 0;
    return out;
  }

  io::UniqueFd fd_;
  EvdevPtr dev_;
  std::string path_;
  bool syncing_ = false;
  std::array<std::atomic<int>, 2> emergency_ids_{-1, -1};
  std::atomic<std::uint64_t> messages_{0};
};

std::string open_error(const std::string& path, int e) {
  std::string s = "evdev: cannot open " + path + ": " + base::errno_text(e);
  if (e == EACCES) s += " (`hapticd udev-rules` writes the rule that gives group hapticd it)";
  return s;
}

}  // namespace

Enumeration enumerate_input_devices() {
  Enumeration out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/dev/input", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("event", 0) != 0) continue;
    io::UniqueFd fd(::open(e.path().c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
    libevdev* raw = nullptr;
    if (!fd || libevdev_new_from_fd(fd.get(), &raw) != 0) {
      ++out.unreadable;
      continue;
    }
    const EvdevPtr dev(raw);
    out.devices.push_back(describe_device(e.path().string(), dev.get(), fd.get()));
  }
  add_links(out.devices, "/dev/input/by-id");
  add_links(out.devices, "/dev/input/by-path");
  std::sort(out.devices.begin(), out.devices.end(),
            [](const InputListing& a, const InputListing& b) { return a.path < b.path; });
  return out;
}

std::unique_ptr<EvdevTransport> open_libevdev(const EvdevSettings& s, InputListing& listing) {
  std::error_code ec;
  const std::string resolved =
      s.select.path.empty() ? std::string() : fs::canonical(s.select.path, ec).string();
  if (!s.select.path.empty() && ec) {
    throw DeviceError("evdev: device.evdev.select.path " + s.select.path + ": " + ec.message());
  }
  const Enumeration all = enumerate_input_devices();
  const Selection sel = select_one(s.select, resolved, all.devices);
  if (!sel.device) {
    if (!resolved.empty() && all.unreadable > 0) {
      // A path the enumeration could not open says why itself.
      io::UniqueFd probe(::open(resolved.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC));
      if (!probe) throw DeviceError(open_error(resolved, errno));
    }
    throw DeviceError("evdev: " + sel.error);
  }
  listing = *sel.device;
  io::UniqueFd fd(::open(listing.path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC));
  if (!fd) throw DeviceError(open_error(listing.path, errno));
  libevdev* raw = nullptr;
  if (const int rc = libevdev_new_from_fd(fd.get(), &raw); rc != 0) {
    throw DeviceError("evdev: libevdev on " + listing.path + ": " + base::errno_text(-rc));
  }
  EvdevPtr dev(raw);
  if (const int rc = libevdev_set_clock_id(dev.get(), CLOCK_MONOTONIC); rc != 0) {
    throw DeviceError("evdev: EVIOCSCLOCKID on " + listing.path + ": " + base::errno_text(-rc));
  }
  return std::make_unique<LibevdevTransport>(std::move(fd), std::move(dev), listing.path);
}

}  // namespace hapticd::drivers::evdev
