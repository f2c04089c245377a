#include "sim/peers/hid/uhid_peer.h"

#include <fcntl.h>
#include <linux/uhid.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>

#include "base/errno_text.h"
#include "drivers/device.h"

namespace hapticd::sim::hid {
namespace {

void write_event(int fd, const uhid_event& e) {
  if (::write(fd, &e, sizeof e) != static_cast<ssize_t>(sizeof e)) {
    throw std::system_error(errno, std::system_category(), "hid peer: write /dev/uhid");
  }
}

// uhid's structures are packed: copy through a pointer, leaving room for the NUL.
void copy_text(std::uint8_t* to, std::size_t capacity, const std::string& s) {
  std::memcpy(to, s.data(), std::min(s.size(), capacity - 1));
}

}  // namespace

UhidPeer::UhidPeer(const std::string& path, const DeviceIdentity& id,
                   std::unique_ptr<HidFirmware> firmware)
    : FirmwarePeer(std::move(firmware)),
      fd_(::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC)) {
  if (!fd_) {
    throw DeviceError("hid peer: cannot open " + path + ": " + base::errno_text(errno) +
                      " (the uhid module, and root or the uhid group)");
  }
  const std::vector<std::uint8_t>& d = fw_->descriptor();
  uhid_event e{};
  e.type = UHID_CREATE2;
  copy_text(e.u.create2.name, sizeof e.u.create2.name, id.name);
  copy_text(e.u.create2.uniq, sizeof e.u.create2.uniq, id.serial);
  e.u.create2.rd_size = static_cast<std::uint16_t>(d.size());
  e.u.create2.bus = 0x03;  // BUS_USB: hidapi lists it with its USB ids
  e.u.create2.vendor = id.vendor_id;
  e.u.create2.product = id.product_id;
  std::memcpy(e.u.create2.rd_data, d.data(), std::min(d.size(), sizeof e.u.create2.rd_data));
  try {
    write_event(fd_.get(), e);
  } catch (const std::system_error& err) {
    throw DeviceError(err.what());
  }
}

UhidPeer::~UhidPeer() {
  uhid_event e{};
  e.type = UHID_DESTROY;
  [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &e, sizeof e);
}

void UhidPeer::send_input(std::span<const std::uint8_t> report) {
  uhid_event e{};
  e.type = UHID_INPUT2;
  e.u.input2.size = static_cast<std::uint16_t>(std::min(report.size(), sizeof e.u.input2.data));
  std::memcpy(e.u.input2.data, report.data(), e.u.input2.size);
  write_event(fd_.get(), e);
}

void UhidPeer::service() {
  const auto to_host = [this](std::span<const std::uint8_t> r) { send_input(r); };
  const auto now = std::chrono::steady_clock::now();
  uhid_event e{};
  while (!destroyed_.load()) {
    const ssize_t n = ::read(fd_.get(), &e, sizeof e);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) break;
    if (n < 0) throw std::system_error(errno, std::system_category(), "hid peer: read /dev/uhid");
    if (e.type == UHID_OUTPUT || e.type == UHID_SET_REPORT || e.type == UHID_GET_REPORT) {
      fw_->heard_host(now);
    }
    switch (e.type) {
      case UHID_OUTPUT:
        fw_->on_output({e.u.output.data, e.u.output.size}, to_host);
        break;
      case UHID_SET_REPORT: {
        const auto& r = e.u.set_report;
        const int status = fw_->on_set_feature({r.data, r.size}, to_host);
        uhid_event reply{};
        reply.type = UHID_SET_REPORT_REPLY;
        reply.u.set_report_reply.id = r.id;
        reply.u.set_report_reply.err = static_cast<std::uint16_t>(status);
        write_event(fd_.get(), reply);
        break;
      }
      case UHID_GET_REPORT: {
        std::vector<std::uint8_t> report;
        const int status = fw_->on_get_feature(e.u.get_report.rnum, report);
        uhid_event reply{};
        reply.type = UHID_GET_REPORT_REPLY;
        reply.u.get_report_reply.id = e.u.get_report.id;
        reply.u.get_report_reply.err = static_cast<std::uint16_t>(status);
        reply.u.get_report_reply.size = static_cast<std::uint16_t>(
            std::min(report.size(), sizeof reply.u.get_report_reply.data));
        std::memcpy(reply.u.get_report_reply.data, report.data(), reply.u.get_report_reply.size);
        write_event(fd_.get(), reply);
        break;
      }
      default:
        break;  // START, STOP, OPEN, CLOSE: a USB device never learns of these either
    }
  }
  fw_->check_watchdog(now);
}

bool UhidPeer::inject(PeerFault fault) noexcept {
  if (fault != PeerFault::kTransportFault) return fw_->inject(fault);
  destroyed_.store(true);
  fw_->vanish();
  uhid_event e{};
  e.type = UHID_DESTROY;
  [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &e, sizeof e);
  return true;
}

}  // namespace hapticd::sim::hid
