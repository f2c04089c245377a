// The simulated device's control endpoint (ep0) through the raw gadget: descriptors,
// configuration, and the HID class requests (GET_REPORT and SET_REPORT of feature and output
// reports, which the firmware answers). See raw_gadget_peer.h.
#include <linux/hid.h>
#include <linux/usb/ch9.h>
#include <sys/ioctl.h>

#include "sim/peers/hid/raw_gadget_io.h"
#include "sim/peers/hid/raw_gadget_peer.h"

namespace hapticd::sim::hid {

using raw_gadget_io::gadget_broken;
using raw_gadget_io::kMaxTransfer;
using raw_gadget_io::Transfer;

namespace {
constexpr std::uint8_t kOutputReport = 2, kFeatureReport = 3;  // HID 1.11 7.2.1
}  // namespace

void RawGadgetPeer::reply(const usb_ctrlrequest& r, std::span<const std::uint8_t> data) {
  if (r.wLength == 0) {  // the raw gadget takes an IN request without data as an OUT one
    acknowledge();
    return;
  }
  const std::size_t n = std::min({data.size(), std::size_t{r.wLength}, kMaxTransfer});
  // Shorter than asked and a whole number of packets: a zero-length packet ends it, or the
  // host waits for more until its time-out.
  Transfer t(0, n, n < r.wLength && n % 64 == 0);
  std::memcpy(t.data(), data.data(), n);
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_WRITE, t.arg()) < 0) ep0_error("ep0 write");
}

void RawGadgetPeer::ep0_error(const char* what) {
  if (gadget_broken(errno)) fail(what);
}

void RawGadgetPeer::acknowledge() {
  Transfer t(0, 0);
  if (ioctl(gadget_.get(), USB_RAW_IOCTL_EP0_READ, t.arg()) < 0) ep0_error("ep0 ack");
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
      // 0 is the address state: the data threads wait for the next configuration.
      if (r.wValue == 0) {
        link_up_.store(false);
      } else if (r.wValue != UsbHidDescriptors::kConfiguration || !configure()) {
        return false;
      }
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
      if (r.wValue != 0) return false;  // one alternate setting
      acknowledge();
      return true;
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
        ep0_error("ep0 read");
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

}  // namespace hapticd::sim::hid
