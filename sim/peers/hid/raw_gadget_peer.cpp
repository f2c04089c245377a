#include "sim/peers/hid/raw_gadget_peer.h"

#include <fcntl.h>
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

#include "base/errno_text.h"
#include "drivers/device.h"
#include "sim/peers/hid/raw_gadget_io.h"

namespace hapticd::sim::hid {

using raw_gadget_io::gadget_broken;
using raw_gadget_io::kMaxTransfer;
using raw_gadget_io::Transfer;

namespace {

constexpr std::size_t kInQueue = 4;  // input reports waiting for IN polls; older drop

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
    : FirmwarePeer(std::move(firmware)),
      usb_(make_usb_hid_descriptors(id, fw_->descriptor())),
      gadget_(::open(path.c_str(), O_RDWR | O_CLOEXEC)),
      timer_(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
  if (!gadget_) {
    throw DeviceError("hid peer: cannot open " + path + ": " + base::errno_text(errno) +
                      " (the raw_gadget module, and root)");
  }
  if (!timer_) throw DeviceError(std::string("hid peer: eventfd: ") + base::errno_text(errno));
  const auto [udc, driver] = first_udc();
  usb_raw_init init{};
  copy_name(init.driver_name, driver);
  copy_name(init.device_name, udc);
  init.speed = USB_SPEED_FULL;
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_INIT, &init) < 0 ||
      ioctl(gadget_.get(), USB_RAW_IOCTL_RUN, 0) < 0) {
    throw DeviceError("hid peer: the raw gadget cannot bind to " + udc + " (" + driver +
                      "): " + base::errno_text(errno) + " (is another gadget bound to it?)");
  }
  install_wake_handler();
  control_ = std::thread([this] { control_loop(); });
}

RawGadgetPeer::~RawGadgetPeer() { unplug(); }

void RawGadgetPeer::unplug() noexcept {
  if (unplugged_.exchange(true)) return;
  fw_->vanish();  // what the person feels at once
  {
    // Under the lock the data threads wait with: a notify between their check and their
    // wait would otherwise be lost (SIGURG does not end a condition variable's wait).
    const std::lock_guard lock(queue_mutex_);
    stopping_.store(true);
  }
  queue_ready_.notify_all();
  stop_thread(control_, control_done_);  // it started the other two; it has ended now
  stop_thread(in_, in_done_);
  stop_thread(out_, out_done_);
  gadget_.reset();  // the gadget driver unregisters: a disconnect on the host's side
  const std::lock_guard lock(fw_mutex_);
  fw_->lose_host();  // an output report handled while the threads stopped set nothing again
  fw_->vanish();
}

void RawGadgetPeer::stop() noexcept { unplug(); }

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
  if (error_.empty()) error_ = "hid peer: " + what + ": " + base::errno_text(errno);
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
    if (!answered) ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_STALL, 0);  // nothing to answer
  }
  control_done_.store(true);
}

bool RawGadgetPeer::configure() {
  if (configured_.load()) {
    // Again, after a bus reset or a configuration 0: the endpoints stay enabled; the data
    // threads, parked since their transfers were cancelled, may queue again.
    {
      const std::lock_guard lock(queue_mutex_);
      generation_.fetch_add(1);
      link_up_.store(true);
    }
    queue_ready_.notify_all();
    return true;
  }
  in_handle_ = enable_endpoint(gadget_.get(), usb_.in_endpoint);
  out_handle_ = enable_endpoint(gadget_.get(), usb_.out_endpoint);
  if (in_handle_ < 0 || out_handle_ < 0) {
    fail("enabling the interrupt endpoints");
    return false;
  }
  ioctl(gadget_.get(), USB_RAW_IOCTL_VBUS_DRAW, 50);  // units of 2 mA: bMaxPower's 100 mA
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_CONFIGURE, 0) < 0) {
    fail("configure");
    return false;
  }
  link_up_.store(true);
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

void RawGadgetPeer::link_lost(std::uint64_t generation) {
  // A transfer queued while the controller is still resetting fails the whole raw gadget
  // (dummy_hcd refuses for 50 ms, and raw_gadget marks itself failed): wait for the host's
  // next SET_CONFIGURATION, unless it came already while this transfer was being cancelled.
  std::unique_lock lock(queue_mutex_);
  if (generation_.load() == generation) link_up_.store(false);
  queue_ready_.wait(lock, [&] { return stopping_.load() || generation_.load() != generation; });
}

void RawGadgetPeer::in_loop() {
  unblock_wake_signal();
  while (!stopping_.load()) {
    std::vector<std::uint8_t> next;
    {
      std::unique_lock lock(queue_mutex_);
      queue_ready_.wait(
          lock, [this] { return stopping_.load() || (link_up_.load() && !queue_.empty()); });
      if (stopping_.load()) break;
      next = std::move(queue_.front());
      queue_.pop_front();
    }
    const std::uint64_t generation = generation_.load();
    Transfer t(in_handle_, next.size());
    std::memcpy(t.data(), next.data(), std::min(next.size(), kMaxTransfer));
    // Blocks until the host's next IN poll takes it (only while the device is open).
    if (ioctl(gadget_.get(), USB_RAW_IOCTL_EP_WRITE, t.arg()) < 0 && errno != EINTR) {
      if (gadget_broken(errno)) {
        fail("interrupt IN");
        break;
      }
      link_lost(generation);  // ESHUTDOWN, ECONNRESET: a reset or a disconnect cancelled it
    }
  }
  in_done_.store(true);
}

void RawGadgetPeer::out_loop() {
  unblock_wake_signal();
  const auto to_host = [this](std::span<const std::uint8_t> in) { queue_input(in); };
  while (!stopping_.load()) {
    const std::uint64_t generation = generation_.load();
    Transfer t(out_handle_, UsbHidDescriptors::kMaxPacket);
    const int n = ioctl(gadget_.get(), USB_RAW_IOCTL_EP_READ, t.arg());
    if (n < 0) {
      if (errno == EINTR) continue;
      if (gadget_broken(errno)) {
        fail("interrupt OUT");
        break;
      }
      link_lost(generation);  // queue again only once the host has configured it again
      continue;
    }
    const std::lock_guard lock(fw_mutex_);
    fw_->heard_host(std::chrono::steady_clock::now());
    fw_->on_output({t.data(), static_cast<std::size_t>(n)}, to_host);
  }
  out_done_.store(true);
}

}  // namespace hapticd::sim::hid
