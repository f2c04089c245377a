#include "raw_usb_ftdi.h"

#include "raw_gadget_io.h"

#include <fcntl.h>
#include <linux/usb/ch9.h>
#include <linux/usb/raw_gadget.h>
#include <pthread.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace hapticd::reference::falcon {
namespace {

using namespace gadget;

}  // namespace

bool listed_in_sysfs(const FtdiIdentity& id) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/sys/bus/usb/devices", ec)) {
    std::ifstream v(e.path() / "idVendor"), p(e.path() / "idProduct");
    unsigned vendor = 0, product = 0;
    if (v >> std::hex >> vendor && p >> std::hex >> product && vendor == id.vendor_id &&
        product == id.product_id) {
      return true;
    }
  }
  return false;
}

RawUsbFtdi::RawUsbFtdi(const FirmwareOptions& options, const FtdiIdentity& id)
    : id_(id), firmware_(options) {
  // USB 2.0 9.6.1: full speed, class 0 (the interface says vendor-specific), one configuration.
  device_desc_ = {18, USB_DT_DEVICE};
  put16(device_desc_, 0x0200);
  device_desc_.insert(device_desc_.end(), {0, 0, 0, kMaxPacket});
  put16(device_desc_, id_.vendor_id);
  put16(device_desc_, id_.product_id);
  put16(device_desc_, id_.release);
  device_desc_.insert(device_desc_.end(), {1, 2, 3, 1});
  // 9.6.3 configuration, 9.6.5 one interface of class 0xFF, 9.6.6 the two bulk endpoints.
  config_desc_ = {9, USB_DT_CONFIG, 0, 0, 1, kConfigValue, 0, 0x80, 45};
  config_desc_.insert(config_desc_.end(), {9, USB_DT_INTERFACE, 0, 0, 2, 0xFF, 0xFF, 0xFF, 2});
  config_desc_.insert(config_desc_.end(), {7, USB_DT_ENDPOINT, kInAddress, 2, kMaxPacket, 0, 0});
  config_desc_.insert(config_desc_.end(), {7, USB_DT_ENDPOINT, kOutAddress, 2, kMaxPacket, 0, 0});
  config_desc_[2] = static_cast<std::uint8_t>(config_desc_.size());

  fd_ = start_gadget();
  control_ = std::thread([this] { control_loop(); });
}

RawUsbFtdi::~RawUsbFtdi() { unplug(); }

void RawUsbFtdi::unplug() noexcept {
  if (unplugged_.exchange(true)) return;
  {
    const std::lock_guard lock(m_);
    stopping_.store(true);
    link_up_.store(false);
  }
  cv_.notify_all();
  end_thread(control_, control_done_);
  end_thread(in_, in_done_);
  end_thread(out_, out_done_);
  ::close(fd_);  // the gadget driver unregisters: the host sees the device go
}

std::string RawUsbFtdi::error() const {
  const std::lock_guard lock(error_m_);
  return error_;
}

void RawUsbFtdi::fail(const char* what) {
  const std::lock_guard lock(error_m_);
  if (error_.empty()) error_ = std::string(what) + ": " + std::strerror(errno);
}

double RawUsbFtdi::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool RawUsbFtdi::configure() {
  if (!endpoints_.load()) {
    const auto enable = [this](std::uint8_t address) {
      usb_endpoint_descriptor d{};
      d.bLength = USB_DT_ENDPOINT_SIZE;
      d.bDescriptorType = USB_DT_ENDPOINT;
      d.bEndpointAddress = address;
      d.bmAttributes = USB_ENDPOINT_XFER_BULK;
      d.wMaxPacketSize = kMaxPacket;
      return ioctl(fd_, USB_RAW_IOCTL_EP_ENABLE, &d);
    };
    in_ep_ = enable(kInAddress);
    out_ep_ = enable(kOutAddress);
    if (in_ep_ < 0 || out_ep_ < 0 || ioctl(fd_, USB_RAW_IOCTL_VBUS_DRAW, 45) < 0 ||
        ioctl(fd_, USB_RAW_IOCTL_CONFIGURE, 0) < 0) {
      fail("configuring the endpoints");
      return false;
    }
    endpoints_.store(true);
    in_ = std::thread([this] { in_loop(); });
    out_ = std::thread([this] { out_loop(); });
  }
  {
    const std::lock_guard lock(m_);
    ++generation_;
    link_up_.store(true);
  }
  cv_.notify_all();
  return true;
}

// A transfer cancelled by a bus reset: wait until the host configures the device again.
void RawUsbFtdi::wait_for_host(std::uint64_t generation) {
  std::unique_lock lock(m_);
  if (generation_ == generation) link_up_.store(false);
  cv_.wait(lock, [&] { return stopping_.load() || generation_ != generation; });
}

// Waits for the next IN packet. While the firmware runs: the slot dummy_hcd keeps (see the
// header) first gets a bare status (`decoy`), then data as soon as there is some, or a bare
// status once the latency timer has run out. Before (the bootloader): only answers, at once.
// False when stopping.
bool RawUsbFtdi::next_packet(std::vector<std::uint8_t>& packet, std::uint64_t& generation,
                             bool slot_taken, bool& decoy) {
  std::unique_lock lock(m_);
  decoy = false;
  while (true) {
    if (stopping_.load()) return false;
    if (!link_up_.load()) {
      cv_.wait(lock);
      continue;
    }
    const bool running = firmware_.stage() == Stage::kRunning;
    if (running && !slot_taken) {
      decoy = true;
      break;
    }
    if (firmware_.pending() > 0) break;
    const auto due = last_in_ + std::chrono::milliseconds(firmware_.latency_ms());
    if (running && std::chrono::steady_clock::now() >= due) break;
    if (running) {
      cv_.wait_until(lock, due);
    } else {
      cv_.wait(lock);
    }
  }
  packet.assign(kModemStatus.begin(), kModemStatus.end());
  const auto data =
      decoy ? std::vector<std::uint8_t>{} : firmware_.take(kMaxPacket - kModemStatus.size());
  packet.insert(packet.end(), data.begin(), data.end());
  in_flight_ = true;
  in_flight_status_ = data.empty();
  in_flight_purges_ = firmware_.purges();
  ++in_seq_;
  generation = generation_;
  return true;
}

void RawUsbFtdi::in_loop() {
  accept_wake();
  std::vector<std::uint8_t> packet;
  std::uint64_t generation = 0;
  bool slot_taken = false, decoy = false;  // what dummy_hcd's one-packet slot holds
  while (next_packet(packet, generation, slot_taken, decoy)) {
    Io io(in_ep_, packet.size());
    std::memcpy(io.data(), packet.data(), packet.size());
    const int n = ioctl(fd_, USB_RAW_IOCTL_EP_WRITE, &io.block);
    const int e = errno;
    bool status = false;
    {
      const std::lock_guard lock(m_);
      status = in_flight_status_;
      in_flight_ = false;
      // Data taken back by a withdrawal meant for an earlier bare status (the signal can land
      // late) is not lost: only a purge discards it.
      if (n < 0 && e == EINTR && !status && firmware_.purges() == in_flight_purges_) {
        firmware_.put_back(std::span(packet).subspan(kModemStatus.size()));
      }
      last_in_ = std::chrono::steady_clock::now();
    }
    cv_.notify_all();
    if (n >= 0) {
      // The decoy sits in the slot; anything after it completed once the host had both.
      slot_taken = decoy;
      (status ? status_packets_ : data_packets_).fetch_add(1);
    } else if (e == EINTR) {
      withdrawn_.fetch_add(1);  // taken back (purge, data behind it) or stopping
    } else if (broken(e)) {
      errno = e;
      fail("bulk IN");
      break;
    } else {
      slot_taken = false;
      wait_for_host(generation);
    }
  }
  in_done_.store(true);
}

// Takes back the IN packet queued now (any, or only a status-only one), not the ones queued
// after it: SIGURG makes the raw gadget dequeue it; repeated until the IN thread is out of the
// ioctl, as the signal may land just before it blocks.
void RawUsbFtdi::withdraw(bool status_only) {
  std::uint64_t target = 0;
  {
    const std::lock_guard lock(m_);
    target = in_seq_;
  }
  while (true) {
    {
      const std::lock_guard lock(m_);
      if (stopping_.load() || !in_flight_ || in_seq_ != target) return;
      if (status_only && !in_flight_status_) return;
    }
    pthread_kill(in_.native_handle(), SIGURG);
    usleep(200);
  }
}

void RawUsbFtdi::out_loop() {
  accept_wake();
  while (!stopping_.load()) {
    std::uint64_t generation = 0;
    {
      const std::lock_guard lock(m_);
      generation = generation_;
    }
    // One packet per read: a bulk write of whole packets has no short packet to end it.
    Io io(out_ep_, kMaxPacket);
    const int n = ioctl(fd_, USB_RAW_IOCTL_EP_READ, &io.block);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (broken(errno)) {
        fail("bulk OUT");
        break;
      }
      wait_for_host(generation);
      continue;
    }
    bool answered = false;
    {
      const std::lock_guard lock(m_);
      firmware_.receive({io.data(), static_cast<std::size_t>(n)}, now());
      answered = firmware_.pending() > 0;
    }
    cv_.notify_all();
    if (answered) withdraw(true);  // the answer goes out in place of a bare status
  }
  out_done_.store(true);
}

}  // namespace hapticd::reference::falcon
