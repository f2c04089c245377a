#include "sim/peers/hid/raw_gadget_peer.h"

#include <fcntl.h>
#include <linux/hid.h>
#include <linux/usb/ch9.h>
#include <linux/usb/raw_gadget.h>
#include <pthread.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "drivers/device.h"

namespace hapticd::sim::hid {
namespace {

constexpr std::size_t kMaxTransfer = 4096;  // a report, a descriptor: far below this
constexpr std::size_t kInQueue = 4;         // input reports waiting for IN polls; older drop
constexpr std::uint8_t kOutputReport = 2, kFeatureReport = 3;  // HID 1.11 7.2.1

// A raw gadget transfer as the ioctls take it: the kernel's header (which ends in a flexible
// array) followed by the data, in one block. The header is copied in, never aliased.
class Transfer {
 public:
  Transfer(int ep, std::size_t length) {
    const usb_raw_ep_io h{static_cast<__u16>(ep), 0,
                          static_cast<__u32>(std::min(length, kMaxTransfer))};
    std::memcpy(bytes_.data(), &h, sizeof h);
  }
  void* arg() noexcept { return bytes_.data(); }
  std::uint8_t* data() noexcept { return bytes_.data() + sizeof(usb_raw_ep_io); }
  std::size_t capacity() const noexcept { return kMaxTransfer; }

 private:
  alignas(usb_raw_ep_io) std::array<std::uint8_t, sizeof(usb_raw_ep_io) + kMaxTransfer> bytes_{};
};

void on_wake(int) {}  // only interrupts the ioctl

void install_wake_handler() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction sa {};
    sa.sa_handler = on_wake;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: a blocked ioctl returns EINTR
    sigaction(SIGURG, &sa, nullptr);
  });
}

void unblock_wake_signal() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGURG);
  pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
}

// Signals `t` until it has ended (a signal sent just before it blocks would be missed), then
// joins it.
void stop_thread(std::thread& t, const std::atomic<bool>& done) noexcept {
  if (!t.joinable()) return;
  while (!done.load()) {
    pthread_kill(t.native_handle(), SIGURG);
    usleep(2000);
  }
  t.join();
}

// The first USB device controller: its name (/sys/class/udc/<name>) and its driver's name,
// which the raw gadget matches against the controller's gadget name.
std::pair<std::string, std::string> first_udc() {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator("/sys/class/udc", ec)) {
    const fs::path driver = fs::read_symlink(e.path() / "device" / "driver", ec);
    if (!ec) return {e.path().filename().string(), driver.filename().string()};
  }
  throw DeviceError(
      "hid peer: no USB device controller in /sys/class/udc (load dummy_hcd, or use a board "
      "with a UDC)");
}

void copy_name(std::uint8_t* to, const std::string& s) {
  std::memcpy(to, s.data(), std::min(s.size(), std::size_t{UDC_NAME_LENGTH_MAX - 1}));
}

int enable_endpoint(int fd, const std::vector<std::uint8_t>& d) {
  usb_endpoint_descriptor e{};
  e.bLength = USB_DT_ENDPOINT_SIZE;
  e.bDescriptorType = USB_DT_ENDPOINT;
  e.bEndpointAddress = d[2];
  e.bmAttributes = d[3];
  e.wMaxPacketSize = static_cast<__le16>(d[4] | d[5] << 8);
  e.bInterval = d[6];
  return ioctl(fd, USB_RAW_IOCTL_EP_ENABLE, &e);
}

}  // namespace

RawGadgetPeer::RawGadgetPeer(const std::string& path, const DeviceIdentity& id,
                             std::unique_ptr<HidFirmware> firmware)
    : usb_(make_usb_hid_descriptors(id, firmware->descriptor())),
      gadget_(::open(path.c_str(), O_RDWR | O_CLOEXEC)),
      timer_(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)),
      fw_(std::move(firmware)) {
  if (!gadget_) {
    throw DeviceError("hid peer: cannot open " + path + ": " + std::strerror(errno) +
                      " (the raw_gadget module, and root)");
  }
  const auto [udc, driver] = first_udc();
  usb_raw_init init{};
  copy_name(init.driver_name, driver);
  copy_name(init.device_name, udc);
  init.speed = USB_SPEED_FULL;
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_INIT, &init) < 0 ||
      ioctl(gadget_.get(), USB_RAW_IOCTL_RUN, 0) < 0) {
    throw DeviceError("hid peer: the raw gadget cannot bind to " + udc + " (" + driver +
                      "): " + std::strerror(errno) + " (is another gadget bound to it?)");
  }
  install_wake_handler();
  control_ = std::thread([this] { control_loop(); });
}

RawGadgetPeer::~RawGadgetPeer() { unplug(); }

void RawGadgetPeer::unplug() noexcept {
  if (unplugged_.exchange(true)) return;
  fw_->vanish();
  stopping_.store(true);
  queue_ready_.notify_all();
  stop_thread(control_, control_done_);  // it started the other two; it has ended now
  stop_thread(in_, in_done_);
  stop_thread(out_, out_done_);
  gadget_.reset();  // the gadget driver unregisters: a disconnect on the host's side
}

bool RawGadgetPeer::inject(PeerFault fault) noexcept {
  if (fault != PeerFault::kTransportFault) return fw_->inject(fault);
  unplug();
  return true;
}

void RawGadgetPeer::service() {
  {
    const std::lock_guard lock(error_mutex_);
    if (!error_.empty()) throw DeviceError(error_);
  }
  const std::lock_guard lock(fw_mutex_);
  fw_->check_watchdog(std::chrono::steady_clock::now());
}

void RawGadgetPeer::fail(const std::string& what) {
  const std::lock_guard lock(error_mutex_);
  if (error_.empty()) error_ = "hid peer: " + what + ": " + std::strerror(errno);
}

void RawGadgetPeer::control_loop() {
  unblock_wake_signal();
  alignas(usb_raw_event) std::array<std::uint8_t, sizeof(usb_raw_event) + sizeof(usb_ctrlrequest)>
      bytes{};
  while (!stopping_.load()) {
    const usb_raw_event header{USB_RAW_EVENT_INVALID, sizeof(usb_ctrlrequest)};
    std::memcpy(bytes.data(), &header, sizeof header);
    if (ioctl(gadget_.get(), USB_RAW_IOCTL_EVENT_FETCH, bytes.data()) < 0) {
      if (errno == EINTR) continue;
      fail("raw gadget event");
      break;
    }
    usb_raw_event got{};
    std::memcpy(&got, bytes.data(), sizeof got);
    if (got.type != USB_RAW_EVENT_CONTROL) continue;  // CONNECT: nothing to do
    usb_ctrlrequest r{};
    std::memcpy(&r, bytes.data() + sizeof got, sizeof r);
    const unsigned type = r.bRequestType & USB_TYPE_MASK;
    const bool answered = type == USB_TYPE_STANDARD ? answer_standard(r)
                          : type == USB_TYPE_CLASS  ? answer_class(r)
                                                    : false;
    if (!answered) {
      stalls_.fetch_add(1);
      ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_STALL, 0);
    }
  }
  control_done_.store(true);
}

void RawGadgetPeer::reply(const usb_ctrlrequest& r, std::span<const std::uint8_t> data) {
  const std::size_t n = std::min({data.size(), std::size_t{r.wLength}, kMaxTransfer});
  Transfer t(0, n);
  std::memcpy(t.data(), data.data(), n);
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_WRITE, t.arg()) < 0 && errno != EINTR) {
    fail("ep0 write");
  }
}

void RawGadgetPeer::acknowledge() {
  Transfer t(0, 0);
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_READ, t.arg()) < 0 && errno != EINTR) fail("ep0 ack");
}

bool RawGadgetPeer::answer_standard(const usb_ctrlrequest& r) {
  static constexpr std::uint8_t kZeros[2] = {0, 0};
  const unsigned kind = r.wValue >> 8, index = r.wValue & 0xFF;
  switch (r.bRequest) {
    case USB_REQ_GET_DESCRIPTOR: {
      const std::vector<std::uint8_t>* d = kind == USB_DT_DEVICE   ? &usb_.device
                                           : kind == USB_DT_CONFIG ? &usb_.configuration
                                           : kind == HID_DT_HID    ? &usb_.hid
                                           : kind == HID_DT_REPORT ? &usb_.report
                                                                   : nullptr;
      if (kind == USB_DT_STRING) {
        const auto s = usb_.string(static_cast<std::uint8_t>(index));
        if (!s) return false;
        reply(r, *s);
        return true;
      }
      if (d == nullptr) return false;  // a device qualifier: a full-speed device has none
      reply(r, *d);
      return true;
    }
    case USB_REQ_SET_CONFIGURATION:
      if (r.wValue != UsbHidDescriptors::kConfiguration || !configure()) return false;
      acknowledge();
      return true;
    case USB_REQ_GET_CONFIGURATION: {
      const std::uint8_t c = configured_.load() ? UsbHidDescriptors::kConfiguration : 0;
      reply(r, {&c, 1});
      return true;
    }
    case USB_REQ_GET_STATUS:
    case USB_REQ_GET_INTERFACE:
      reply(r, {kZeros, r.bRequest == USB_REQ_GET_STATUS ? 2u : 1u});
      return true;
    case USB_REQ_SET_INTERFACE:
    case USB_REQ_CLEAR_FEATURE:
    case USB_REQ_SET_FEATURE:
      if (r.bRequestType & USB_DIR_IN) return false;
      acknowledge();
      return true;
    default:
      return false;
  }
}

bool RawGadgetPeer::answer_class(const usb_ctrlrequest& r) {
  const std::uint8_t report_type = static_cast<std::uint8_t>(r.wValue >> 8);
  const std::uint8_t report_id = static_cast<std::uint8_t>(r.wValue & 0xFF);
  const auto to_host = [this](std::span<const std::uint8_t> in) { queue_input(in); };
  switch (r.bRequest) {
    case HID_REQ_GET_REPORT: {
      if (report_type != kFeatureReport) return false;  // input reports go by interrupt IN
      std::vector<std::uint8_t> report;
      {
        const std::lock_guard lock(fw_mutex_);
        fw_->heard_host(std::chrono::steady_clock::now());
        if (fw_->on_get_feature(report_id, report) != 0) return false;
      }
      reply(r, report);
      return true;
    }
    case HID_REQ_SET_REPORT: {
      if (report_type != kOutputReport && report_type != kFeatureReport) return false;
      Transfer t(0, r.wLength);
      const int n = ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_READ, t.arg());
      if (n < 0) {
        if (errno != EINTR) fail("ep0 read");
        return true;  // the data stage was taken: too late to stall
      }
      const std::span<const std::uint8_t> report(t.data(), static_cast<std::size_t>(n));
      const std::lock_guard lock(fw_mutex_);
      fw_->heard_host(std::chrono::steady_clock::now());
      // A refused feature report cannot be stalled after its data stage; the firmware has
      // counted it, and the host reads the device's state back where it matters (Block Load).
      if (report_type == kOutputReport) {
        fw_->on_output(report, to_host);
      } else {
        fw_->on_set_feature(report, to_host);
      }
      return true;
    }
    case HID_REQ_SET_IDLE:
    case HID_REQ_SET_PROTOCOL:
      acknowledge();
      return true;
    case HID_REQ_GET_IDLE:
    case HID_REQ_GET_PROTOCOL: {
      const std::uint8_t v =
          r.bRequest == HID_REQ_GET_PROTOCOL ? 1 : 0;  // report protocol; no idle
      reply(r, {&v, 1});
      return true;
    }
    default:
      return false;
  }
}

bool RawGadgetPeer::configure() {
  if (configured_.load()) return true;  // the host may set it again after a reset
  in_handle_ = enable_endpoint(gadget_.get(), usb_.in_endpoint);
  out_handle_ = enable_endpoint(gadget_.get(), usb_.out_endpoint);
  if (in_handle_ < 0 || out_handle_ < 0) {
    fail("enabling the interrupt endpoints");
    return false;
  }
  ioctl(gadget_.get(), USB_RAW_IOCTL_VBUS_DRAW, 100);
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_CONFIGURE, 0) < 0) {
    fail("configure");
    return false;
  }
  in_ = std::thread([this] { in_loop(); });
  out_ = std::thread([this] { out_loop(); });
  configured_.store(true);
  return true;
}

void RawGadgetPeer::queue_input(std::span<const std::uint8_t> report) {
  {
    const std::lock_guard lock(queue_mutex_);
    if (queue_.size() >= kInQueue) {
      queue_.pop_front();  // the host is not polling: the oldest answer is the least useful
      fw_->count_dropped();
    }
    queue_.emplace_back(report.begin(), report.end());
  }
  queue_ready_.notify_one();
}

void RawGadgetPeer::in_loop() {
  unblock_wake_signal();
  while (!stopping_.load()) {
    std::vector<std::uint8_t> next;
    {
      std::unique_lock lock(queue_mutex_);
      queue_ready_.wait(lock, [this] { return stopping_.load() || !queue_.empty(); });
      if (stopping_.load()) break;
      next = std::move(queue_.front());
      queue_.pop_front();
    }
    Transfer t(in_handle_, next.size());
    std::memcpy(t.data(), next.data(), std::min(next.size(), kMaxTransfer));
    // Blocks until the host's next IN poll takes it (only while the device is open).
    if (ioctl(gadget_.get(), USB_RAW_IOCTL_EP_WRITE, t.arg()) < 0 && errno != EINTR &&
        errno != ESHUTDOWN) {
      fail("interrupt IN");
      break;
    }
  }
  in_done_.store(true);
}

void RawGadgetPeer::out_loop() {
  unblock_wake_signal();
  const auto to_host = [this](std::span<const std::uint8_t> in) { queue_input(in); };
  while (!stopping_.load()) {
    Transfer t(out_handle_, UsbHidDescriptors::kMaxPacket);
    const int n = ioctl(gadget_.get(), USB_RAW_IOCTL_EP_READ, t.arg());
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == ESHUTDOWN) {  // the host has gone (unbound, reset): wait for it
        usleep(5000);
        continue;
      }
      fail("interrupt OUT");
      break;
    }
    const std::lock_guard lock(fw_mutex_);
    fw_->heard_host(std::chrono::steady_clock::now());
    fw_->on_output({t.data(), static_cast<std::size_t>(n)}, to_host);
  }
  out_done_.store(true);
}

}  // namespace hapticd::sim::hid
