#include "drivers/hid/hidapi_transport.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <hidapi/hidapi.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

#include "base/errno_text.h"
#include "base/hex.h"
#include "drivers/device.h"
#include "drivers/hid/report_descriptor.h"
#include "drivers/hid/sysfs_descriptor.h"
#include "drivers/io/output_thread.h"

namespace hapticd::drivers::hid {
namespace {

// The hidapi functions the driver calls, looked up in the chosen backend's library.
struct Api {
  decltype(&hid_init) init = nullptr;
  decltype(&hid_enumerate) enumerate = nullptr;
  decltype(&hid_free_enumeration) free_enumeration = nullptr;
  decltype(&hid_open_path) open_path = nullptr;
  decltype(&hid_close) close = nullptr;
  decltype(&hid_write) write = nullptr;
  decltype(&hid_read_timeout) read_timeout = nullptr;
  decltype(&hid_send_feature_report) send_feature = nullptr;
  decltype(&hid_get_feature_report) get_feature = nullptr;
  decltype(&hid_error) error = nullptr;
  decltype(&hid_version_str) version = nullptr;
  // hidapi 0.14 and later only.
  int (*get_report_descriptor)(hid_device*, unsigned char*, size_t) = nullptr;
};

const char* library_of(Backend b) {
  return b == Backend::kHidraw ? "libhidapi-hidraw.so.0" : "libhidapi-libusb.so.0";
}

template <typename F>
void bind(void* lib, const char* name, F& out, Backend b) {
  out = reinterpret_cast<F>(dlsym(lib, name));
  if (out == nullptr) {
    throw DeviceError(std::string("hid: ") + library_of(b) + " has no " + name +
                      " (hidapi too old?)");
  }
}

Api load(Backend b) {
  // RTLD_LOCAL: the other backend's identically named symbols never interpose.
  void* lib = dlopen(library_of(b), RTLD_NOW | RTLD_LOCAL);
  if (lib == nullptr) {
    throw DeviceError(std::string("hid: cannot load hidapi's ") + to_string(b) + " backend (" +
                      dlerror() + "); install Debian's " +
                      (b == Backend::kHidraw ? "libhidapi-hidraw0" : "libhidapi-libusb0"));
  }
  Api a;
  bind(lib, "hid_init", a.init, b);
  bind(lib, "hid_enumerate", a.enumerate, b);
  bind(lib, "hid_free_enumeration", a.free_enumeration, b);
  bind(lib, "hid_open_path", a.open_path, b);
  bind(lib, "hid_close", a.close, b);
  bind(lib, "hid_write", a.write, b);
  bind(lib, "hid_read_timeout", a.read_timeout, b);
  bind(lib, "hid_send_feature_report", a.send_feature, b);
  bind(lib, "hid_get_feature_report", a.get_feature, b);
  bind(lib, "hid_error", a.error, b);
  bind(lib, "hid_version_str", a.version, b);
  a.get_report_descriptor =
      reinterpret_cast<decltype(a.get_report_descriptor)>(dlsym(lib, "hid_get_report_descriptor"));
  if (a.init() != 0) {
    throw DeviceError(std::string("hid: hid_init failed for the ") + to_string(b) + " backend");
  }
  return a;  // the library stays loaded for the life of the process
}

// Loaded once per backend, on first use (never on the RT thread).
const Api& api(Backend b) {
  static std::mutex m;
  static std::optional<Api> apis[2];
  const std::lock_guard lock(m);
  std::optional<Api>& a = apis[b == Backend::kHidraw ? 0 : 1];
  if (!a) a = load(b);
  return *a;
}

const char* bus_name(const hid_device_info* d) {
#if HID_API_VERSION >= HID_API_MAKE_VERSION(0, 13, 0)
  switch (d->bus_type) {
    case HID_API_BUS_USB:
      return "usb";
    case HID_API_BUS_BLUETOOTH:
      return "bluetooth";
    case HID_API_BUS_I2C:
      return "i2c";
    case HID_API_BUS_SPI:
      return "spi";
    default:
      return "";
  }
#else
  (void)d;
  return "";
#endif
}

}  // namespace

std::vector<DeviceListing> enumerate_devices(Backend backend) {
  const Api& a = api(backend);
  std::vector<DeviceListing> out;
  hid_device_info* list = a.enumerate(0, 0);
  for (const hid_device_info* d = list; d != nullptr; d = d->next) {
    DeviceListing l;
    l.path = d->path != nullptr ? d->path : "";
    l.vendor_id = d->vendor_id;
    l.product_id = d->product_id;
    l.release = d->release_number;
    l.serial = to_utf8(d->serial_number);
    l.manufacturer = to_utf8(d->manufacturer_string);
    l.product = to_utf8(d->product_string);
    l.interface = d->interface_number;
    l.usage_page = d->usage_page;
    l.usage = d->usage;
    l.bus = bus_name(d);
    out.push_back(std::move(l));
  }
  a.free_enumeration(list);
  return out;
}

namespace {

// Output reports between the RT thread (producer) and the writer thread (consumer): a
// single-producer single-consumer ring of preallocated slots. The RT side never waits.
class HidapiTransport final : public HidTransport {
 public:
  HidapiTransport(const Api& a, Backend b, hid_device* dev, DeviceListing listing,
                  std::optional<std::vector<std::uint8_t>> descriptor, const HidSettings& s);
  ~HidapiTransport() override;

  std::string describe() const override { return description_; }
  std::vector<std::uint8_t> report_descriptor() override;
  void set_feature(std::span<const std::uint8_t> report) override;
  std::vector<std::uint8_t> get_feature(std::uint8_t id, std::size_t length) override;
  bool flush(std::chrono::milliseconds timeout) noexcept override;
  IoResult read(std::span<std::uint8_t> buffer) noexcept override;
  IoResult write(std::span<const std::uint8_t> report) noexcept override;
  void set_safe_reports(std::vector<std::vector<std::uint8_t>> reports) override;
  void write_safe() noexcept override;
  void emergency() noexcept override;
  std::string last_error() const override;

 private:
  static constexpr std::size_t kSlotBytes = kMaxReportData + 1;
  void run();
  void wake() noexcept;
  // Writer thread: sends one report; false (and the transport failed) on an error.
  bool send(const std::uint8_t* data, std::size_t size);
  void fail(const std::string& what, int code);

  const Api& api_;
  hid_device* dev_;
  std::string path_, description_;
  std::optional<std::vector<std::uint8_t>> descriptor_;
  int emergency_fd_ = -1;  // hidraw only: the same node, for the crash handler's write(2)
  int wake_fd_ = -1;       // eventfd: the RT thread's "something to send"

  std::vector<std::uint8_t> slots_;  // capacity_ slots of kSlotBytes
  std::vector<std::size_t> sizes_;
  std::size_t capacity_;
  std::atomic<std::uint64_t> head_{0}, tail_{0};
  std::atomic<std::uint64_t> safe_cut_{0};  // head_ at write_safe(): what the safe reports drop
  std::atomic<bool> safe_pending_{false}, stop_{false}, failed_{false};
  std::atomic<int> error_code_{0};
  std::vector<std::vector<std::uint8_t>> safe_;

  mutable std::mutex m_;  // writer <-> flush() and last_error(); never taken on the RT thread
  std::condition_variable idle_cv_;
  bool busy_ = false;
  std::string error_text_;
  std::thread writer_;
};

HidapiTransport::HidapiTransport(const Api& a, Backend b, hid_device* dev, DeviceListing l,
                                 std::optional<std::vector<std::uint8_t>> descriptor,
                                 const HidSettings& s)
    : api_(a),
      dev_(dev),
      path_(l.path),
      descriptor_(std::move(descriptor)),
      slots_(static_cast<std::size_t>(s.limits.out_queue) * kSlotBytes),
      sizes_(static_cast<std::size_t>(s.limits.out_queue)),
      capacity_(static_cast<std::size_t>(s.limits.out_queue)) {
  // USB ids as lsusb shows them.
  const std::string ids = base::hex(l.vendor_id, 4, base::HexCase::kLower).substr(2) + ":" +
                          base::hex(l.product_id, 4, base::HexCase::kLower).substr(2);
  description_ = "hid " + ids + (l.product.empty() ? "" : " '" + l.product + "'") +
                 (l.serial.empty() ? "" : " serial '" + l.serial + "'") + " at " + l.path + " (" +
                 to_string(b) + ", hidapi " + a.version() + ")";
  if (b == Backend::kHidraw)
    emergency_fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK);
  wake_fd_ = eventfd(0, EFD_CLOEXEC);
  if (wake_fd_ < 0) {
    if (emergency_fd_ >= 0) ::close(emergency_fd_);
    throw DeviceError(std::string("hid: eventfd: ") + base::errno_text(errno));
  }
  // Without the privilege for its priority the writer competes as an ordinary thread
  // (counted as OUT-queue-full ticks if it falls behind).
  writer_ = io::start_output_thread("hapticd-hidout", s.writer_priority, [this] { run(); });
}

HidapiTransport::~HidapiTransport() {
  stop_.store(true);
  wake();
  writer_.join();
  ::close(wake_fd_);
  if (emergency_fd_ >= 0) ::close(emergency_fd_);
  api_.close(dev_);
}

void HidapiTransport::wake() noexcept {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
}

void HidapiTransport::fail(const std::string& what, int code) {
  {
    const std::lock_guard lock(m_);
    error_text_ = what;
  }
  error_code_.store(code);
  failed_.store(true);
}

bool HidapiTransport::send(const std::uint8_t* data, std::size_t size) {
  // hidapi's libusb backend sets no errno of its own (and 0.13's hid_error says only "not
  // implemented yet"): without this a stale EAGAIN named an unplugged device.
  errno = 0;
  if (api_.write(dev_, data, size) >= 0) return true;
  const int e = errno != 0 && errno != EAGAIN ? errno : EIO;
  fail("hid_write: " + to_utf8(api_.error(dev_)), e);
  return false;
}

void HidapiTransport::run() {
  while (!stop_.load()) {
    std::uint64_t n = 0;
    [[maybe_unused]] const ssize_t r = ::read(wake_fd_, &n, sizeof n);  // blocks until woken
    {
      const std::lock_guard lock(m_);
      busy_ = true;
    }
    while (!stop_.load() && !failed_.load()) {
      if (safe_pending_.exchange(false)) {
        // Drop what was queued before write_safe(), never what came after it (disable's
        // Block Free follows the safe reports at once, and must reach the device).
        const std::uint64_t cut = safe_cut_.load(std::memory_order_acquire);
        if (tail_.load(std::memory_order_relaxed) < cut) {
          tail_.store(cut, std::memory_order_release);
        }
        for (const auto& s : safe_) {
          if (!send(s.data(), s.size())) break;
        }
        continue;
      }
      const std::uint64_t t = tail_.load(std::memory_order_relaxed);
      if (t == head_.load(std::memory_order_acquire)) break;
      const std::size_t slot = t % capacity_;
      send(&slots_[slot * kSlotBytes], sizes_[slot]);
      tail_.store(t + 1, std::memory_order_release);
    }
    {
      const std::lock_guard lock(m_);
      busy_ = false;
    }
    idle_cv_.notify_all();
  }
}

bool HidapiTransport::flush(std::chrono::milliseconds timeout) noexcept {
  std::unique_lock lock(m_);
  return idle_cv_.wait_for(lock, timeout, [&] {
    return failed_.load() || (!busy_ && !safe_pending_.load() && tail_.load() == head_.load());
  }) && !failed_.load();
}

IoResult HidapiTransport::write(std::span<const std::uint8_t> report) noexcept {
  if (failed_.load(std::memory_order_relaxed)) return {TransportIo::kError, 0, error_code_.load()};
  if (report.size() > kSlotBytes) return {TransportIo::kError, 0, EMSGSIZE};
  const std::uint64_t h = head_.load(std::memory_order_relaxed);
  if (h - tail_.load(std::memory_order_acquire) >= capacity_) return {TransportIo::kEmpty, 0, 0};
  const std::size_t slot = h % capacity_;
  std::memcpy(&slots_[slot * kSlotBytes], report.data(), report.size());
  sizes_[slot] = report.size();
  head_.store(h + 1, std::memory_order_release);
  wake();
  return {TransportIo::kOk, report.size(), 0};
}

void HidapiTransport::set_safe_reports(std::vector<std::vector<std::uint8_t>> reports) {
  flush(std::chrono::milliseconds(100));  // the writer is not reading safe_ while we swap it
  const std::lock_guard lock(m_);
  safe_ = std::move(reports);
}

void HidapiTransport::write_safe() noexcept {
  safe_cut_.store(head_.load(std::memory_order_relaxed), std::memory_order_release);
  safe_pending_.store(true);
  wake();
}

void HidapiTransport::emergency() noexcept {
  if (emergency_fd_ < 0) return;
  for (const auto& s : safe_) {
    // hidraw takes the report id in byte 0 exactly as hid_write does.
    [[maybe_unused]] const ssize_t n = ::write(emergency_fd_, s.data(), s.size());
  }
}

IoResult HidapiTransport::read(std::span<std::uint8_t> buffer) noexcept {
  errno = 0;
  const int n = api_.read_timeout(dev_, buffer.data(), buffer.size(), 0);
  if (n > 0) return {TransportIo::kOk, static_cast<std::size_t>(n), 0};
  if (n == 0) return {TransportIo::kEmpty, 0, 0};
  return {TransportIo::kError, 0, errno != 0 ? errno : EIO};
}

std::vector<std::uint8_t> HidapiTransport::report_descriptor() {
  if (api_.get_report_descriptor != nullptr) {
    std::vector<std::uint8_t> buf(kMaxDescriptorSize);
    const int n = api_.get_report_descriptor(dev_, buf.data(), buf.size());
    if (n > 0) {
      buf.resize(static_cast<std::size_t>(n));
      return buf;
    }
  }
  if (descriptor_) return *descriptor_;
  throw DeviceError("hid: cannot read the report descriptor of " + path_ + ": hidapi " +
                    api_.version() +
                    " has no hid_get_report_descriptor and the kernel has no "
                    "copy in sysfs (no driver bound to the device before it was opened)");
}

void HidapiTransport::set_feature(std::span<const std::uint8_t> report) {
  if (api_.send_feature(dev_, report.data(), report.size()) < 0) {
    throw DeviceError("hid: feature report " + std::to_string(report.empty() ? 0 : report[0]) +
                      " to " + path_ + ": " + to_utf8(api_.error(dev_)));
  }
}

std::vector<std::uint8_t> HidapiTransport::get_feature(std::uint8_t id, std::size_t length) {
  std::vector<std::uint8_t> buf(std::max<std::size_t>(length, 1));
  buf[0] = id;
  const int n = api_.get_feature(dev_, buf.data(), buf.size());
  if (n < 0) {
    throw DeviceError("hid: reading feature report " + std::to_string(id) + " from " + path_ +
                      ": " + to_utf8(api_.error(dev_)));
  }
  buf.resize(static_cast<std::size_t>(n));
  return buf;
}

std::string HidapiTransport::last_error() const {
  const std::lock_guard lock(m_);
  return error_text_;
}

}  // namespace

std::unique_ptr<HidTransport> open_hidapi(const HidSettings& s) {
  const Api& a = api(s.backend);
  const Selection sel = select_one(s.select, enumerate_devices(s.backend), to_string(s.backend));
  if (!sel.device) throw DeviceError("hid: " + sel.error);
  const std::string& path = sel.device->path;
  // Before opening: the libusb backend detaches usbhid, and with it the kernel's copy.
  auto descriptor = kernel_report_descriptor(path, s.backend == Backend::kLibusb);
  hid_device* dev = a.open_path(path.c_str());
  if (dev == nullptr) {
    throw DeviceError("hid: cannot open " + path + " (" + to_utf8(a.error(nullptr)) +
                      "): is the user in group hapticd, and are the rules `hapticd udev-rules` "
                      "writes for this configuration installed?");
  }
  try {
    return std::make_unique<HidapiTransport>(a, s.backend, dev, *sel.device, std::move(descriptor),
                                             s);
  } catch (...) {
    a.close(dev);
    throw;
  }
}

}  // namespace hapticd::drivers::hid
