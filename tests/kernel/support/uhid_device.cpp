#include "uhid_device.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "hid_support.h"
#include "sysfs.h"

namespace hapticd::kernel_test {
namespace {

template <std::size_t N>
void copy_string(std::uint8_t (&field)[N], const std::string& text) {
  std::memcpy(field, text.c_str(), std::min(text.size() + 1, N - 1));
}

}  // namespace

UhidDevice::UhidDevice(UhidConfig config) : config_(std::move(config)) {
  require_path("/dev/uhid", "uhid (the uhid module)");
  if (config_.report_descriptor.size() > HID_MAX_DESCRIPTOR_SIZE) {
    throw KernelFacilityError("report descriptor longer than HID_MAX_DESCRIPTOR_SIZE");
  }
  fd_.reset(::open("/dev/uhid", O_RDWR | O_NONBLOCK | O_CLOEXEC));
  if (!fd_) throw_errno("open /dev/uhid");

  uhid_event create{};
  create.type = UHID_CREATE2;
  auto& req = create.u.create2;
  copy_string(req.name, config_.name);
  copy_string(req.uniq, config_.serial);
  req.rd_size = static_cast<std::uint16_t>(config_.report_descriptor.size());
  req.bus = config_.bus;
  req.vendor = config_.vendor_id;
  req.product = config_.product_id;
  std::memcpy(req.rd_data, config_.report_descriptor.data(), config_.report_descriptor.size());
  write_event(create, "UHID_CREATE2");

  // The kernel answers with UHID_START once a HID driver (hid-generic) took the device.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    const auto event = next_event(std::max(left, std::chrono::milliseconds(0)));
    if (!event) throw KernelFacilityError("uhid: no UHID_START within 10 s");
    if (event->type == UHID_START) break;
  }
  wait_until(
      [&] {
        return find_hidraw(config_.bus, config_.vendor_id, config_.product_id, config_.serial)
            .has_value();
      },
      std::chrono::seconds(10), "the hidraw node of uhid device " + config_.name);
  hidraw_path_ = *find_hidraw(config_.bus, config_.vendor_id, config_.product_id, config_.serial);
}

UhidDevice::~UhidDevice() {
  uhid_event destroy{};
  destroy.type = UHID_DESTROY;
  // Best effort: closing /dev/uhid destroys the device as well.
  [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &destroy, sizeof destroy);
}

void UhidDevice::write_event(const uhid_event& event, const char* what) {
  if (::write(fd_.get(), &event, sizeof event) != static_cast<ssize_t>(sizeof event)) {
    throw_errno(std::string("uhid ") + what);
  }
}

std::optional<uhid_event> UhidDevice::next_event(std::chrono::milliseconds timeout) {
  pollfd pfd{fd_.get(), POLLIN, 0};
  const int ready = ::poll(&pfd, 1, static_cast<int>(timeout.count()));
  if (ready < 0) throw_errno("poll /dev/uhid");
  if (ready == 0) return std::nullopt;
  uhid_event event{};
  if (::read(fd_.get(), &event, sizeof event) < 0) throw_errno("read /dev/uhid");
  if (event.type == UHID_OPEN) open_ = true;
  if (event.type == UHID_CLOSE) open_ = false;
  return event;
}

void UhidDevice::send_input(const std::vector<std::uint8_t>& report) {
  uhid_event input{};
  input.type = UHID_INPUT2;
  if (report.size() > sizeof input.u.input2.data) {
    throw KernelFacilityError("input report longer than UHID_DATA_MAX");
  }
  input.u.input2.size = static_cast<std::uint16_t>(report.size());
  std::memcpy(input.u.input2.data, report.data(), report.size());
  write_event(input, "UHID_INPUT2");
}

std::optional<std::vector<std::uint8_t>> UhidDevice::read_output(
    std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() < 0) return std::nullopt;
    const auto event = next_event(left);
    if (!event) return std::nullopt;
    if (event->type == UHID_OUTPUT) {
      const auto& out = event->u.output;
      return std::vector<std::uint8_t>(out.data, out.data + out.size);
    }
  }
}

}  // namespace hapticd::kernel_test
