#include "drivers/falcon/usb_link.h"

#include <fcntl.h>
#include <libusb.h>
#include <linux/usbdevice_fs.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <sstream>
#include <thread>
#include <vector>

#include "base/clock.h"
#include "base/hex.h"
#include "drivers/device.h"
#include "drivers/io/output_thread.h"

namespace hapticd::drivers::falcon {
namespace {

constexpr int kStreamTimeoutMs = 100;          // how often the threads look at the stop flag
constexpr std::size_t kRing = 4096;            // IN data bytes between the reader and the RT thread
constexpr unsigned kEmergencyTimeoutMs = 250;  // a crash handler's one packet (a device that
                                               // takes none: the process ends after it)

std::string usb_error(int code) { return libusb_error_name(code); }

int errno_of(int code) {
  return code == LIBUSB_ERROR_NO_DEVICE ? ENODEV : code == LIBUSB_ERROR_TIMEOUT ? ETIMEDOUT : EIO;
}

std::string serial_of(libusb_device_handle* h, const libusb_device_descriptor& d) {
  unsigned char text[128] = {};
  if (d.iSerialNumber == 0) return {};
  const int n = libusb_get_string_descriptor_ascii(h, d.iSerialNumber, text, sizeof text - 1);
  return n > 0 ? std::string(reinterpret_cast<char*>(text), static_cast<std::size_t>(n)) : "";
}

class UsbLink final : public FalconTransport {
 public:
  // `h` wraps `fd`, the device's usbfs node, which the link closes after it.
  UsbLink(libusb_context* ctx, libusb_device_handle* h, int fd, std::string description,
          int priority)
      : ctx_(ctx), h_(h), fd_(fd), description_(std::move(description)), priority_(priority) {}
  ~UsbLink() override {
    stop_.store(true);
    if (wake_ >= 0) {
      const std::uint64_t one = 1;
      [[maybe_unused]] const ssize_t n = ::write(wake_, &one, sizeof one);
    }
    if (writer_.joinable()) writer_.join();
    if (reader_.joinable()) reader_.join();
    if (wake_ >= 0) ::close(wake_);
    libusb_release_interface(h_, 0);
    libusb_close(h_);  // auto-detach gives a detached kernel driver its device back
    ::close(fd_);      // libusb_close leaves a wrapped descriptor open
    libusb_exit(ctx_);
  }

  bool control(const FtdiRequest& r, std::string& error) override {
    const int rc =
        libusb_control_transfer(h_, kFtdiRequestType, r.request, r.value, 0, nullptr, 0, 1000);
    if (rc >= 0) return true;
    error = usb_error(rc);
    return false;
  }
  bool write(std::span<const unsigned char> data, int timeout_ms, std::string& error) override {
    int done = 0;
    const int rc = libusb_bulk_transfer(h_, kEndpointOut, const_cast<unsigned char*>(data.data()),
                                        static_cast<int>(data.size()), &done, timeout_ms);
    if (rc == 0 && done == static_cast<int>(data.size())) return true;
    error = rc != 0 ? usb_error(rc) : std::to_string(done) + " of " + std::to_string(data.size());
    return false;
  }
  int read(std::span<unsigned char> buffer, int timeout_ms, std::string& error) override {
    int done = 0;
    const int rc = libusb_bulk_transfer(h_, kEndpointIn, buffer.data(),
                                        static_cast<int>(buffer.size()), &done, timeout_ms);
    if (rc == 0 || rc == LIBUSB_ERROR_TIMEOUT) return done;
    error = usb_error(rc);
    return -1;
  }

  std::string describe() const override { return description_; }
  void start() override;
  TransportIo send(const Packet& p) noexcept override;
  TransportIo receive(PacketStream& stream) noexcept override;
  int error() const noexcept override { return error_.load(); }
  std::int64_t received_ns() const noexcept override { return handed_ns_; }
  void emergency(const Packet& p) noexcept override;

 private:
  void write_loop();
  void read_loop();
  // A transfer failed: an unplug often fails the transfers in flight with an I/O error before
  // libusb knows the device is gone, so the handle is asked a few times (this is the reader's
  // or writer's thread, never the loop's) and "gone" said when it is.
  void fail(int code) noexcept {
    for (int i = 0; i < 10 && code != LIBUSB_ERROR_NO_DEVICE; ++i) {
      int configuration = 0;
      if (libusb_get_configuration(h_, &configuration) == LIBUSB_ERROR_NO_DEVICE) {
        code = LIBUSB_ERROR_NO_DEVICE;
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    }
    error_.store(errno_of(code));
    failed_.store(true);
  }

  libusb_context* ctx_;
  libusb_device_handle* h_;
  int fd_;
  std::string description_;
  int priority_;
  int wake_ = -1;
  std::atomic<bool> stop_{false}, failed_{false};
  // The emergency packet must be the last (a crash's, or a stuck loop's: nothing follows it
  // either way): halted_ stops the writer for good, and in_transfer_ (set before the writer
  // looks at halted_) says whether one of its packets is in flight.
  std::atomic<bool> halted_{false}, in_transfer_{false};
  std::atomic<int> error_{0};
  // The newest packet from the RT thread to the writer, a triple buffer: the RT thread fills
  // its back slot and swaps it with the middle (marked fresh); the writer swaps its front slot
  // with a fresh middle. Neither waits, and a packet is never torn; one the writer had not
  // taken yet is replaced by the newer (the Falcon wants the latest torques, not a backlog).
  static constexpr std::uint8_t kFresh = 4;
  std::array<Packet, 3> slots_{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // the RT thread's
  std::uint8_t front_ = 2;  // the writer's
  std::array<unsigned char, kRing> ring_{};
  std::atomic<std::uint64_t> head_{0}, tail_{0};  // bytes written by the reader, read by RT
  std::atomic<std::int64_t> arrived_ns_{0};       // when the reader's last data arrived
  std::int64_t handed_ns_ = 0;                    // that time, as receive() last saw it
  std::thread writer_, reader_;
};

void UsbLink::start() {
  wake_ = ::eventfd(0, EFD_CLOEXEC);
  if (wake_ < 0) throw DeviceError("falcon: eventfd: " + std::string(std::strerror(errno)));
  writer_ = io::start_output_thread("hapticd-falcout", priority_, [this] { write_loop(); });
  reader_ = io::start_output_thread("hapticd-falcin", priority_, [this] { read_loop(); });
}

TransportIo UsbLink::send(const Packet& p) noexcept {
  if (failed_.load()) return TransportIo::kError;
  slots_[back_] = p;
  const std::uint8_t old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
  back_ = old & 3;
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(wake_, &one, sizeof one);
  // The writer had not taken the previous one: the newer goes instead (counted by the caller).
  return (old & kFresh) != 0 ? TransportIo::kEmpty : TransportIo::kOk;
}

TransportIo UsbLink::receive(PacketStream& stream) noexcept {
  // Read before head_: data the reader adds after this time is handed on next tick.
  const std::int64_t arrived = arrived_ns_.load(std::memory_order_acquire);
  const std::uint64_t head = head_.load(std::memory_order_acquire);
  std::uint64_t tail = tail_.load(std::memory_order_relaxed);
  while (tail < head) {
    const std::size_t at = tail % kRing;
    const std::size_t n = std::min<std::uint64_t>(head - tail, kRing - at);
    stream.feed_data({ring_.data() + at, n});
    tail += n;
  }
  if (tail != tail_.load(std::memory_order_relaxed)) handed_ns_ = arrived;
  tail_.store(tail, std::memory_order_release);
  return failed_.load() ? TransportIo::kError : TransportIo::kOk;
}

void UsbLink::write_loop() {
  while (!stop_.load()) {
    std::uint64_t count = 0;
    if (::read(wake_, &count, sizeof count) < 0 && errno != EINTR) return;
    while (!stop_.load() && (middle_.load(std::memory_order_acquire) & kFresh) != 0) {
      in_transfer_.store(true);  // before halted_ is read: emergency() sees one or the other
      if (halted_.load()) {
        in_transfer_.store(false);
        return;
      }
      front_ = middle_.exchange(front_, std::memory_order_acq_rel) & 3;
      int done = 0;
      const int rc = libusb_bulk_transfer(h_, kEndpointOut, slots_[front_].data(), kPacketBytes,
                                          &done, kStreamTimeoutMs);
      in_transfer_.store(false);
      if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) return fail(rc);
    }
  }
}

// libusb is not async-signal-safe; an ioctl on the descriptor libusb drives is: one synchronous
// bulk OUT on the interface this descriptor claimed, once the writer's packet in flight (its
// transfer times out within kStreamTimeoutMs) has gone, so that no torque follows the zero.
// Bounded: on the writer's own thread (a crash there) its flag never clears.
void UsbLink::emergency(const Packet& p) noexcept {
  halted_.store(true);
  const std::int64_t until = base::monotonic_ns() + std::int64_t{kEmergencyTimeoutMs} * 1'000'000;
  const timespec pause{0, 100'000};
  while (in_transfer_.load() && base::monotonic_ns() < until) ::nanosleep(&pause, nullptr);
  usbdevfs_bulktransfer b{};
  b.ep = kEndpointOut;
  b.len = kPacketBytes;
  b.timeout = kEmergencyTimeoutMs;
  b.data = const_cast<unsigned char*>(p.data());
  [[maybe_unused]] const int rc = ::ioctl(fd_, USBDEVFS_BULK, &b);
}

void UsbLink::read_loop() {
  std::array<unsigned char, 8 * kUsbPacketBytes> in{};
  while (!stop_.load()) {
    int done = 0;
    const int rc = libusb_bulk_transfer(h_, kEndpointIn, in.data(), static_cast<int>(in.size()),
                                        &done, kStreamTimeoutMs);
    if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) return fail(rc);
    std::uint64_t head = head_.load(std::memory_order_relaxed);
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    for (int k = 0; k < done; ++k) {
      if (static_cast<std::size_t>(k) % kUsbPacketBytes < kModemStatusBytes) continue;
      if (head - tail >= kRing) break;  // the RT thread stopped draining: drop the rest
      ring_[head % kRing] = in[static_cast<std::size_t>(k)];
      ++head;
    }
    if (done > static_cast<int>(kModemStatusBytes)) {
      arrived_ns_.store(base::monotonic_ns(), std::memory_order_release);
    }
    head_.store(head, std::memory_order_release);
  }
}

// The chosen device again, through a descriptor of its usbfs node opened here, which libusb then
// drives: a crash handler can write to it (UsbLink::emergency). `enumerated` is closed. The
// descriptor (-1 and `error` said when it cannot be had) and the handle that wraps it.
struct Wrapped {
  libusb_device_handle* h = nullptr;
  int fd = -1;
  std::string error;
};
Wrapped wrap_usbfs_node(libusb_context* ctx, libusb_device_handle* enumerated) {
  libusb_device* dev = libusb_get_device(enumerated);
  char path[40];
  std::snprintf(path, sizeof path, "/dev/bus/usb/%03u/%03u",
                static_cast<unsigned>(libusb_get_bus_number(dev)),
                static_cast<unsigned>(libusb_get_device_address(dev)));
  libusb_close(enumerated);
  Wrapped w;
  w.fd = ::open(path, O_RDWR | O_CLOEXEC);
  if (w.fd < 0) {
    w.error = std::string(path) + ": " + std::strerror(errno);
  } else if (const int rc = libusb_wrap_sys_device(ctx, w.fd, &w.h); rc != 0) {
    w.error = std::string(path) + ": libusb_wrap_sys_device: " + usb_error(rc);
    ::close(w.fd);
    w.fd = -1;
  }
  return w;
}

}  // namespace

std::unique_ptr<FalconTransport> open_usb(const FalconSettings& s, int output_priority) {
  libusb_context* ctx = nullptr;
  if (const int rc = libusb_init(&ctx); rc != 0) {
    throw DeviceError("falcon: libusb_init: " + usb_error(rc));
  }
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  libusb_device_handle* chosen = nullptr;
  std::string chosen_serial, seen, denied;
  int matches = 0;
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    if (d.idVendor != kVendorId || d.idProduct != kProductId) continue;
    libusb_device_handle* h = nullptr;
    if (const int rc = libusb_open(list[i], &h); rc != 0) {
      denied = usb_error(rc);
      continue;
    }
    const std::string serial = serial_of(h, d);
    seen += (seen.empty() ? "" : ", ") + (serial.empty() ? "(no serial)" : serial);
    if ((s.serial.empty() || s.serial == serial) && ++matches == 1) {
      chosen = h;
      chosen_serial = serial;
    } else {
      libusb_close(h);
    }
  }
  libusb_free_device_list(list, 1);
  int fd = -1;
  const auto refuse = [&](const std::string& why) {
    if (chosen != nullptr) libusb_close(chosen);
    if (fd >= 0) ::close(fd);
    libusb_exit(ctx);
    throw DeviceError("falcon: " + why);
  };
  if (matches == 0 && !denied.empty()) {
    refuse("a Falcon (0403:cb48) is attached but could not be opened (" + denied +
           "): install the rule `hapticd udev-rules` writes for this configuration");
  }
  if (matches == 0) {
    refuse(s.serial.empty() ? "no Falcon (0403:cb48) attached"
                            : "no Falcon with serial '" + s.serial +
                                  "' (attached: " + (seen.empty() ? "none" : seen) + ")");
  }
  if (matches > 1) refuse("several Falcons attached (" + seen + "): set device.falcon.serial");
  const Wrapped w = wrap_usbfs_node(ctx, chosen);
  chosen = w.h;
  fd = w.fd;
  if (fd < 0) refuse("opening its device node " + w.error);
  libusb_set_auto_detach_kernel_driver(chosen, 1);
  if (const int rc = libusb_claim_interface(chosen, 0); rc != 0) {
    refuse("claiming its interface: " + usb_error(rc) + " (another program holds it?)");
  }
  const std::string description =
      "falcon 0403:cb48 serial " + (chosen_serial.empty() ? std::string("?") : chosen_serial);
  return std::make_unique<UsbLink>(ctx, chosen, fd, description, output_priority);
}

std::string list_falcons() {
  libusb_context* ctx = nullptr;
  if (const int rc = libusb_init(&ctx); rc != 0) {
    return "falcon: libusb cannot be asked (" + usb_error(rc) + ")\n";
  }
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  std::ostringstream out;
  int found = 0;
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    if (d.idVendor != kVendorId || d.idProduct != kProductId) continue;
    ++found;
    out << "falcon 0403:cb48 on bus " << int(libusb_get_bus_number(list[i])) << " address "
        << int(libusb_get_device_address(list[i]));
    libusb_device_handle* h = nullptr;
    if (const int rc = libusb_open(list[i], &h); rc != 0) {
      out << " (cannot open it: " << usb_error(rc) << "; `hapticd udev-rules` grants it)\n";
      continue;
    }
    out << "\n  device.falcon.serial: " << serial_of(h, d) << "\n";
    libusb_close(h);
  }
  if (n > 0) libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  if (found == 0) out << "falcon: no Falcon (0403:cb48) attached\n";
  return out.str();
}

}  // namespace hapticd::drivers::falcon
