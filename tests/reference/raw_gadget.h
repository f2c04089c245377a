// What every reference device on the kernel's raw gadget (/dev/raw-gadget on dummy_hcd in the
// kernel test machine) needs of it, whatever the device: the gadget bound to the first USB
// device controller at full speed, the transfer block of include/uapi/linux/usb/raw_gadget.h
// (usb_raw_ep_io, then the data), USB 2.0 chapter 9's little-endian fields and string
// descriptors, and SIGURG (without SA_RESTART) to end a thread blocked in a raw gadget ioctl.
// hid/raw_usb_hid.h and falcon/raw_usb_ftdi.h are the devices; this is their common floor.
// Not RT code.
#pragma once

#include <fcntl.h>
#include <linux/usb/ch9.h>
#include <linux/usb/raw_gadget.h>
#include <pthread.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace hapticd::reference::gadget {

inline constexpr std::size_t kMaxIo = 4096;  // HID_MAX_DESCRIPTOR_SIZE: the longest ep0 answer

// One raw gadget transfer: the kernel's usb_raw_ep_io header, then the data.
struct Io {
  Io(int ep, std::size_t length, bool zlp = false) {
    usb_raw_ep_io h{};
    h.ep = static_cast<__u16>(ep);
    h.flags = zlp ? USB_RAW_IO_FLAGS_ZERO : 0;
    h.length = static_cast<__u32>(std::min(length, kMaxIo));
    std::memcpy(block.data(), &h, sizeof h);
  }
  std::uint8_t* data() { return block.data() + sizeof(usb_raw_ep_io); }
  alignas(usb_raw_ep_io) std::array<std::uint8_t, sizeof(usb_raw_ep_io) + kMaxIo> block{};
};

// The errors that mean the gadget (not one transfer) is unusable.
inline bool broken(int e) { return e == EINVAL || e == EBUSY || e == ENODEV || e == EFAULT; }

inline void put16(std::vector<std::uint8_t>& v, std::uint16_t x) {
  v.push_back(static_cast<std::uint8_t>(x & 0xFF));
  v.push_back(static_cast<std::uint8_t>(x >> 8));
}

// USB 2.0 9.6.7: ASCII as UTF-16LE.
inline std::vector<std::uint8_t> string_descriptor(const std::string& s) {
  std::vector<std::uint8_t> d{0, USB_DT_STRING};
  for (char c : s) put16(d, static_cast<std::uint8_t>(c));
  d[0] = static_cast<std::uint8_t>(d.size());
  return d;
}

inline void wake(int) {}
inline void install_wake() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction sa {};
    sa.sa_handler = wake;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGURG, &sa, nullptr);  // no SA_RESTART: the blocked ioctl returns EINTR
  });
}
inline void accept_wake() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGURG);
  pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
}
// Interrupts `t` until it says it is done, then joins it.
inline void end_thread(std::thread& t, const std::atomic<bool>& done) {
  if (!t.joinable()) return;
  while (!done.load()) {
    pthread_kill(t.native_handle(), SIGURG);
    usleep(2000);
  }
  t.join();
}

// A raw gadget bound to the first controller in /sys/class/udc at full speed and running: its
// descriptor, SIGURG's handler installed. Throws std::runtime_error when it cannot.
inline int start_gadget() {
  std::string udc, driver;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/sys/class/udc", ec)) {
    const auto link = std::filesystem::read_symlink(e.path() / "device" / "driver", ec);
    if (ec) continue;
    udc = e.path().filename().string();
    driver = link.filename().string();
    break;
  }
  if (udc.empty()) throw std::runtime_error("raw gadget: no USB device controller");
  usb_raw_init init{};
  std::memcpy(init.driver_name, driver.data(),
              std::min<std::size_t>(driver.size(), UDC_NAME_LENGTH_MAX - 1));
  std::memcpy(init.device_name, udc.data(),
              std::min<std::size_t>(udc.size(), UDC_NAME_LENGTH_MAX - 1));
  init.speed = USB_SPEED_FULL;
  // The controller may still be bound to the last gadget (its close unbinds it a little
  // later): a refused run fails that raw gadget for good, so open a new one and try again.
  for (int attempt = 0;; ++attempt) {
    const int fd = ::open("/dev/raw-gadget", O_RDWR | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error(std::string("/dev/raw-gadget: ") + std::strerror(errno));
    if (ioctl(fd, USB_RAW_IOCTL_INIT, &init) == 0 && ioctl(fd, USB_RAW_IOCTL_RUN, 0) == 0) {
      install_wake();
      return fd;
    }
    const int e = errno;
    ::close(fd);
    if (e != EBUSY || attempt == 500) {
      throw std::runtime_error("raw gadget on '" + udc + "': " + std::strerror(e));
    }
    usleep(10'000);
  }
}

}  // namespace hapticd::reference::gadget
