#include "raw_usb_hid.h"

#include "raw_gadget.h"

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
#include <stdexcept>

namespace hapticd::reference {
namespace {

constexpr std::uint8_t kConfigValue = 1;
constexpr std::uint16_t kPacket = 64;  // full speed: ep0 and the interrupt endpoints
constexpr std::uint8_t kInAddress = 0x81, kOutAddress = 0x01;
// HID 1.11: descriptor types 0x21 (HID) and 0x22 (report); class requests.
constexpr std::uint8_t kDtHid = 0x21, kDtReport = 0x22;
constexpr std::uint8_t kGetReport = 0x01, kGetIdle = 0x02, kGetProtocol = 0x03, kSetReport = 0x09,
                       kSetIdle = 0x0A, kSetProtocol = 0x0B;
constexpr std::uint8_t kTypeOutput = 2, kTypeFeature = 3;

using namespace gadget;

}  // namespace

RawUsbHid::RawUsbHid(const UsbIdentity& id, std::vector<std::uint8_t> report_descriptor,
                     UsbHidHandlers handlers, bool report_ids)
    : id_(id),
      report_descriptor_(std::move(report_descriptor)),
      handlers_(std::move(handlers)),
      report_ids_(report_ids) {
  // USB 2.0 9.6.1: a full-speed device of class 0 (the interface says HID), one configuration.
  device_desc_ = {18, USB_DT_DEVICE};
  put16(device_desc_, 0x0200);
  device_desc_.insert(device_desc_.end(), {0, 0, 0, kPacket});
  put16(device_desc_, id_.vendor_id);
  put16(device_desc_, id_.product_id);
  put16(device_desc_, id_.release);
  device_desc_.insert(device_desc_.end(), {1, 2, 3, 1});
  // 9.6.3 configuration, 9.6.5 interface (HID, no boot protocol), HID 1.11 6.2.1 the HID
  // descriptor, 9.6.6 the two interrupt endpoints polled every 1 ms.
  config_desc_ = {9, USB_DT_CONFIG, 0, 0, 1, kConfigValue, 0, 0x80, 50};
  config_desc_.insert(config_desc_.end(), {9, USB_DT_INTERFACE, 0, 0, 2, 3, 0, 0, 0});
  config_desc_.insert(config_desc_.end(), {9, kDtHid, 0x11, 0x01, 0, 1, kDtReport});
  put16(config_desc_, static_cast<std::uint16_t>(report_descriptor_.size()));
  config_desc_.insert(config_desc_.end(), {7, USB_DT_ENDPOINT, kInAddress, 3, kPacket, 0, 1});
  config_desc_.insert(config_desc_.end(), {7, USB_DT_ENDPOINT, kOutAddress, 3, kPacket, 0, 1});
  config_desc_[2] = static_cast<std::uint8_t>(config_desc_.size());

  fd_ = gadget::start_gadget();
  control_ = std::thread([this] { control_loop(); });
}

RawUsbHid::~RawUsbHid() { unplug(); }

void RawUsbHid::unplug() noexcept {
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

std::string RawUsbHid::error() const {
  const std::lock_guard lock(error_m_);
  return error_;
}

void RawUsbHid::fail(const char* what) {
  const std::lock_guard lock(error_m_);
  if (error_.empty()) error_ = std::string(what) + ": " + std::strerror(errno);
}

bool RawUsbHid::send_input(std::span<const std::uint8_t> report) {
  {
    const std::lock_guard lock(m_);
    if (!link_up_.load() || in_slot_) return false;
    in_slot_.emplace(report.begin(), report.end());
  }
  cv_.notify_all();
  return true;
}

void RawUsbHid::reply(std::uint16_t asked, std::span<const std::uint8_t> data) {
  if (asked == 0) return ack();
  const std::size_t n = std::min<std::size_t>({data.size(), asked, kMaxIo});
  Io io(0, n, n < asked && n % kPacket == 0);  // a short answer of whole packets ends in a ZLP
  std::memcpy(io.data(), data.data(), n);
  if (ioctl(fd_, USB_RAW_IOCTL_EP0_WRITE, &io.block) < 0 && broken(errno)) fail("ep0 write");
}

void RawUsbHid::ack() {
  Io io(0, 0);
  if (ioctl(fd_, USB_RAW_IOCTL_EP0_READ, &io.block) < 0 && broken(errno)) fail("ep0 status");
}

void RawUsbHid::control_loop() {
  accept_wake();
  // usb_raw_event ends in a flexible array: the request follows it in one block.
  alignas(usb_raw_event) std::array<std::uint8_t, sizeof(usb_raw_event) + sizeof(usb_ctrlrequest)>
      block{};
  while (!stopping_.load()) {
    usb_raw_event head{};
    head.length = sizeof(usb_ctrlrequest);
    std::memcpy(block.data(), &head, sizeof head);
    if (ioctl(fd_, USB_RAW_IOCTL_EVENT_FETCH, block.data()) < 0) {
      if (errno != EINTR) {
        fail("event fetch");
        break;
      }
      continue;
    }
    std::memcpy(&head, block.data(), sizeof head);
    if (head.type != USB_RAW_EVENT_CONTROL) continue;
    usb_ctrlrequest request{};
    std::memcpy(&request, block.data() + sizeof head, sizeof request);
    const unsigned type = request.bRequestType & USB_TYPE_MASK;
    const bool ok = type == USB_TYPE_STANDARD ? standard(&request)
                    : type == USB_TYPE_CLASS  ? hid_class(&request)
                                              : false;
    if (!ok) ioctl(fd_, USB_RAW_IOCTL_EP0_STALL, 0);
  }
  control_done_.store(true);
}

bool RawUsbHid::standard(const void* p) {
  const auto& r = *static_cast<const usb_ctrlrequest*>(p);
  const std::uint8_t kind = r.wValue >> 8, index = r.wValue & 0xFF;
  switch (r.bRequest) {
    case USB_REQ_GET_DESCRIPTOR:
      if (kind == USB_DT_DEVICE) return reply(r.wLength, device_desc_), true;
      if (kind == USB_DT_CONFIG) return reply(r.wLength, config_desc_), true;
      if (kind == kDtReport) return reply(r.wLength, report_descriptor_), true;
      if (kind == kDtHid) {
        return reply(r.wLength, std::span(config_desc_).subspan(18, 9)), true;
      }
      if (kind == USB_DT_STRING) {
        if (index > 3) return false;
        const std::vector<std::uint8_t> s =
            index == 0 ? std::vector<std::uint8_t>{4, USB_DT_STRING, 0x09, 0x04}  // en-US
                       : string_descriptor(index == 1   ? id_.manufacturer
                                           : index == 2 ? id_.product
                                                        : id_.serial);
        return reply(r.wLength, s), true;
      }
      return false;  // no device qualifier: full speed only
    case USB_REQ_SET_CONFIGURATION:
      if (r.wValue == 0) {
        link_up_.store(false);
      } else if (r.wValue != kConfigValue || !configure()) {
        return false;
      }
      return ack(), true;
    case USB_REQ_GET_CONFIGURATION: {
      const std::uint8_t v = link_up_.load() ? kConfigValue : 0;
      return reply(r.wLength, {&v, 1}), true;
    }
    case USB_REQ_GET_STATUS:
    case USB_REQ_GET_INTERFACE: {
      const std::uint8_t zeros[2] = {0, 0};
      return reply(r.wLength, {zeros, r.bRequest == USB_REQ_GET_STATUS ? 2u : 1u}), true;
    }
    case USB_REQ_SET_INTERFACE:
    case USB_REQ_CLEAR_FEATURE:
    case USB_REQ_SET_FEATURE:
      if ((r.bRequestType & USB_DIR_IN) != 0 || (r.bRequest == USB_REQ_SET_INTERFACE && r.wValue))
        return false;
      return ack(), true;
    default:
      return false;
  }
}

bool RawUsbHid::hid_class(const void* p) {
  const auto& r = *static_cast<const usb_ctrlrequest*>(p);
  const std::uint8_t type = r.wValue >> 8, id = r.wValue & 0xFF;
  switch (r.bRequest) {
    case kGetReport: {
      if (type != kTypeFeature || !handlers_.get_feature) return false;
      std::optional<std::vector<std::uint8_t>> data;
      {
        const std::lock_guard lock(handler_m_);
        data = handlers_.get_feature(id);
      }
      if (!data) return false;
      std::vector<std::uint8_t> out;
      if (report_ids_) out.push_back(id);
      out.insert(out.end(), data->begin(), data->end());
      return reply(r.wLength, out), true;
    }
    case kSetReport: {
      Io io(0, r.wLength);
      const int n = ioctl(fd_, USB_RAW_IOCTL_EP0_READ, &io.block);
      if (n < 0) {
        if (broken(errno)) fail("ep0 read");
        return true;  // the data stage is gone: too late to stall
      }
      const std::span<const std::uint8_t> data(io.data(), static_cast<std::size_t>(n));
      const std::lock_guard lock(handler_m_);
      if (type == kTypeOutput && handlers_.output) handlers_.output(data);
      if (type == kTypeFeature && handlers_.set_feature) handlers_.set_feature(data);
      return true;
    }
    case kSetIdle:
    case kSetProtocol:
      return ack(), true;
    case kGetIdle:
    case kGetProtocol: {
      const std::uint8_t v = r.bRequest == kGetProtocol ? 1 : 0;
      return reply(r.wLength, {&v, 1}), true;
    }
    default:
      return false;
  }
}

bool RawUsbHid::configure() {
  if (!endpoints_.load()) {
    const auto enable = [this](std::uint8_t address) {
      usb_endpoint_descriptor d{};
      d.bLength = USB_DT_ENDPOINT_SIZE;
      d.bDescriptorType = USB_DT_ENDPOINT;
      d.bEndpointAddress = address;
      d.bmAttributes = USB_ENDPOINT_XFER_INT;
      d.wMaxPacketSize = kPacket;
      d.bInterval = 1;
      return ioctl(fd_, USB_RAW_IOCTL_EP_ENABLE, &d);
    };
    in_ep_ = enable(kInAddress);
    out_ep_ = enable(kOutAddress);
    if (in_ep_ < 0 || out_ep_ < 0 || ioctl(fd_, USB_RAW_IOCTL_VBUS_DRAW, 50) < 0 ||
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

// A transfer cancelled by a bus reset: queueing again before the host configures the device
// once more would fail the whole gadget (dummy_hcd refuses while it resets).
void RawUsbHid::wait_for_host(std::uint64_t generation) {
  std::unique_lock lock(m_);
  if (generation_ == generation) link_up_.store(false);
  in_slot_.reset();
  cv_.wait(lock, [&] { return stopping_.load() || generation_ != generation; });
}

void RawUsbHid::in_loop() {
  accept_wake();
  while (!stopping_.load()) {
    std::vector<std::uint8_t> report;
    std::uint64_t generation = 0;
    {
      std::unique_lock lock(m_);
      cv_.wait(lock, [&] { return stopping_.load() || (link_up_.load() && in_slot_); });
      if (stopping_.load()) break;
      report = *in_slot_;  // the slot stays taken until the host has the report
      generation = generation_;
    }
    Io io(in_ep_, report.size());
    std::memcpy(io.data(), report.data(), std::min(report.size(), kMaxIo));
    if (ioctl(fd_, USB_RAW_IOCTL_EP_WRITE, &io.block) < 0 && errno != EINTR) {
      if (broken(errno)) {
        fail("interrupt IN");
        break;
      }
      wait_for_host(generation);
      continue;
    }
    const std::lock_guard lock(m_);
    in_slot_.reset();
  }
  in_done_.store(true);
}

void RawUsbHid::out_loop() {
  accept_wake();
  while (!stopping_.load()) {
    std::uint64_t generation = 0;
    {
      const std::lock_guard lock(m_);
      generation = generation_;
    }
    Io io(out_ep_, kPacket);
    const int n = ioctl(fd_, USB_RAW_IOCTL_EP_READ, &io.block);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (broken(errno)) {
        fail("interrupt OUT");
        break;
      }
      wait_for_host(generation);
      continue;
    }
    const std::lock_guard lock(handler_m_);
    if (handlers_.output) handlers_.output({io.data(), static_cast<std::size_t>(n)});
  }
  out_done_.store(true);
}

}  // namespace hapticd::reference
