// The raw gadget's transfer block and the constants both halves of raw_usb_ftdi.cpp use
// (include/uapi/linux/usb/raw_gadget.h: usb_raw_ep_io, then the data).
#pragma once

#include <linux/usb/raw_gadget.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace hapticd::reference::falcon::gadget {

constexpr std::uint8_t kConfigValue = 1;
constexpr std::uint16_t kMaxPacket = 64;  // full speed: ep0 and both bulk endpoints
constexpr std::uint8_t kInAddress = 0x81, kOutAddress = 0x02;
constexpr std::array<std::uint8_t, 2> kModemStatus{0x31, 0x60};
// Vendor IN requests a host may make of an FT232 (libftdi's numbers).
constexpr std::uint8_t kGetModemStatus = 5, kGetLatency = 10, kReadEeprom = 0x90;
constexpr std::size_t kMaxIo = 1024;

struct Io {
  Io(int ep, std::size_t length) {
    usb_raw_ep_io h{};
    h.ep = static_cast<__u16>(ep);
    h.length = static_cast<__u32>(std::min(length, kMaxIo));
    std::memcpy(block.data(), &h, sizeof h);
  }
  std::uint8_t* data() { return block.data() + sizeof(usb_raw_ep_io); }
  alignas(usb_raw_ep_io) std::array<std::uint8_t, sizeof(usb_raw_ep_io) + kMaxIo> block{};
};

inline bool broken(int e) { return e == EINVAL || e == EBUSY || e == ENODEV || e == EFAULT; }

inline void put16(std::vector<std::uint8_t>& v, std::uint16_t x) {
  v.push_back(static_cast<std::uint8_t>(x & 0xFF));
  v.push_back(static_cast<std::uint8_t>(x >> 8));
}

// SIGURG, without SA_RESTART, ends a thread's blocked raw gadget ioctl with EINTR.
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
inline void end_thread(std::thread& t, const std::atomic<bool>& done) {
  if (!t.joinable()) return;
  while (!done.load()) {
    pthread_kill(t.native_handle(), SIGURG);
    usleep(2000);
  }
  t.join();
}

}  // namespace hapticd::reference::falcon::gadget
