#include "pwm_sim.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cstdio>

#include "sysfs.h"
#include "unique_fd.h"

namespace hapticd::kernel_test {
namespace {

PwmApplied parse(const std::string& text, const std::string& path) {
  PwmApplied out;
  unsigned long long period = 0, duty = 0, applies = 0;
  char polarity[16] = {};
  int enabled = 0;
  if (std::sscanf(text.c_str(), "period=%llu duty_cycle=%llu polarity=%15s enabled=%d applies=%llu",
                  &period, &duty, polarity, &enabled, &applies) != 5) {
    throw KernelFacilityError("cannot parse " + path + ": '" + text + "'");
  }
  out.period_ns = period;
  out.duty_cycle_ns = duty;
  out.inversed = std::string(polarity) == "inversed";
  out.enabled = enabled != 0;
  out.applies = applies;
  return out;
}

}  // namespace

PwmSim::PwmSim() : device_("/sys/devices/platform/hapticd-pwm-sim") {
  require_path(device_, "the PWM simulator (hapticd-pwm-sim module)");
  const auto chips = list_dir(device_ + "/pwm");
  if (chips.size() != 1) throw KernelFacilityError("hapticd-pwm-sim has no pwmchip");
  chip_path_ = "/sys/class/pwm/" + chips.front();
}

unsigned PwmSim::npwm() const {
  return static_cast<unsigned>(std::stoul(read_text(chip_path_ + "/npwm")));
}

std::string PwmSim::channel_file(unsigned channel) const {
  return device_ + "/channel" + std::to_string(channel);
}

PwmApplied PwmSim::applied(unsigned channel) const {
  const std::string path = channel_file(channel);
  return parse(read_text(path), path);
}

std::optional<PwmApplied> PwmSim::wait_applied(unsigned channel, std::uint64_t after,
                                               std::chrono::milliseconds timeout) const {
  const std::string path = channel_file(channel);
  UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd) throw_errno("open " + path);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    // sysfs poll: read the file, then poll for POLLPRI, which sysfs_notify() raises.
    char buf[256];
    const ssize_t n = ::pread(fd.get(), buf, sizeof buf - 1, 0);
    if (n < 0) throw_errno("read " + path);
    buf[n] = '\0';
    const PwmApplied state = parse(buf, path);
    if (state.applies > after) return state;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return std::nullopt;
    // No lost wake-up: sysfs compares the notify count with the one at our last read.
    pollfd pfd{fd.get(), POLLPRI | POLLERR, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(left.count()));
    if (ready < 0) throw_errno("poll " + path);
    if (ready == 0) return std::nullopt;  // not notified: the module did not sysfs_notify()
  }
}

}  // namespace hapticd::kernel_test
