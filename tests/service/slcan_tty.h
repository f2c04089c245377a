// A CAN controller's driver with no hardware: slcan, the kernel's driver of serial-line CAN
// adapters, on a pseudo-terminal. It registers through can-dev (link kind "can"), as every
// controller does; what it sends comes out on the terminal's master side in slcan's ASCII,
// which a thread reads as the adapter would: slcan waits for its commands (bitrate, open) to
// drain before `ip link set up` returns. The kernel test machine loads slcan at boot.
#pragma once

#include <fcntl.h>
#include <linux/tty.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

namespace hapticd::service {

class Slcan {
 public:
  Slcan() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) return;
    slave_ = ::open(::ptsname(master_), O_RDWR | O_NOCTTY | O_CLOEXEC);
    int disc = N_SLCAN;
    char name[IFNAMSIZ] = {};
    if (slave_ < 0 || ::ioctl(slave_, TIOCSETD, &disc) != 0 ||
        ::ioctl(slave_, SIOCGIFNAME, name) != 0) {
      return;
    }
    name_ = name;
    reader_ = std::thread([this] {
      char buf[1024];
      while (!stop_.load()) {
        const ssize_t n = ::read(master_, buf, sizeof buf);
        if (n > 0) {
          const std::lock_guard lock(mutex_);
          written_.append(buf, static_cast<std::size_t>(n));
        } else {
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
      }
    });
  }
  ~Slcan() {
    stop_.store(true);
    if (reader_.joinable()) reader_.join();
    if (slave_ >= 0) ::close(slave_);  // the line discipline goes, and the interface with it
    if (master_ >= 0) ::close(master_);
  }
  const std::string& name() const { return name_; }
  std::string written() {
    const std::lock_guard lock(mutex_);
    return written_;
  }

 private:
  int master_ = -1, slave_ = -1;
  std::string name_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::string written_;
  std::thread reader_;
};

}  // namespace hapticd::service
