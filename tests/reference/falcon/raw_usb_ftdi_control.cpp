// ep0 of the reference Falcon's FT232 (raw_usb_ftdi.h): USB 2.0 chapter 9's standard requests
// and the FTDI vendor requests, handed to the firmware model.
#include <linux/usb/ch9.h>
#include <sys/ioctl.h>

#include "raw_gadget_io.h"
#include "raw_usb_ftdi.h"

namespace hapticd::reference::falcon {
namespace {

using namespace gadget;

}  // namespace

void RawUsbFtdi::reply(std::uint16_t asked, const std::vector<std::uint8_t>& data) {
  if (asked == 0) return ack();
  const std::size_t n = std::min<std::size_t>({data.size(), asked, kMaxIo});
  Io io(0, n);
  std::memcpy(io.data(), data.data(), n);
  if (ioctl(fd_, USB_RAW_IOCTL_EP0_WRITE, &io.block) < 0 && broken(errno)) fail("ep0 write");
}

void RawUsbFtdi::ack() {
  Io io(0, 0);
  if (ioctl(fd_, USB_RAW_IOCTL_EP0_READ, &io.block) < 0 && broken(errno)) fail("ep0 status");
}

void RawUsbFtdi::control_loop() {
  accept_wake();
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
                    : type == USB_TYPE_VENDOR ? vendor(&request)
                                              : false;
    if (!ok) ioctl(fd_, USB_RAW_IOCTL_EP0_STALL, 0);
  }
  control_done_.store(true);
}

bool RawUsbFtdi::standard(const void* p) {
  const auto& r = *static_cast<const usb_ctrlrequest*>(p);
  const std::uint8_t kind = r.wValue >> 8, index = r.wValue & 0xFF;
  switch (r.bRequest) {
    case USB_REQ_GET_DESCRIPTOR:
      if (kind == USB_DT_DEVICE) return reply(r.wLength, device_desc_), true;
      if (kind == USB_DT_CONFIG) return reply(r.wLength, config_desc_), true;
      if (kind == USB_DT_STRING && index <= 3) {
        reply(r.wLength, index == 0   ? std::vector<std::uint8_t>{4, USB_DT_STRING, 0x09, 0x04}
                         : index == 1 ? string_descriptor(id_.manufacturer)
                         : index == 2 ? string_descriptor(id_.product)
                                      : string_descriptor(id_.serial));
        return true;
      }
      return false;  // no device qualifier: full speed only
    case USB_REQ_SET_CONFIGURATION:
      if (r.wValue == 0) {
        link_up_.store(false);
      } else if (r.wValue != kConfigValue || !configure()) {
        return false;
      }
      return ack(), true;
    case USB_REQ_GET_CONFIGURATION:
      return reply(r.wLength, {static_cast<std::uint8_t>(link_up_.load() ? kConfigValue : 0)}),
             true;
    case USB_REQ_GET_STATUS:
      return reply(r.wLength, {0, 0}), true;
    case USB_REQ_GET_INTERFACE:
      return reply(r.wLength, {0}), true;
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

bool RawUsbFtdi::vendor(const void* p) {
  const auto& r = *static_cast<const usb_ctrlrequest*>(p);
  if ((r.bRequestType & USB_DIR_IN) != 0) {
    if (r.bRequest == kGetModemStatus)
      return reply(r.wLength, {kModemStatus[0], kModemStatus[1]}), true;
    if (r.bRequest == kGetLatency) {
      const std::uint8_t l = with_firmware([](FalconFirmware& f) { return f.latency_ms(); });
      return reply(r.wLength, {l}), true;
    }
    if (r.bRequest == kReadEeprom) return reply(r.wLength, {0xFF, 0xFF}), true;  // blank
    return false;
  }
  bool ok = false, purged = false;
  {
    const std::lock_guard lock(m_);
    const std::uint64_t purges = firmware_.purges();
    ok = firmware_.control(r.bRequest, r.wValue);
    purged = firmware_.purges() != purges;
  }
  if (!ok) return false;
  cv_.notify_all();  // the firmware may have started: the IN side paces differently
  ack();
  // A purge empties the chip: the packet it had queued goes too.
  if (purged) withdraw(false);
  return true;
}

}  // namespace hapticd::reference::falcon
