// GpioKernelPeer: the GPIO wires through gpio-sim and the PWM simulator (gpio_peer.h).
#include <fcntl.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <system_error>

#include "base/clock.h"
#include "base/errno_text.h"
#include "drivers/device.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/gpio/gpio_peer.h"
#include "sim/peers/gpio/peer_checks.h"

namespace hapticd::sim::gpio {
namespace {

io::UniqueFd open_or_throw(const std::string& path, int flags) {
  io::UniqueFd fd(::open(path.c_str(), flags | O_CLOEXEC));
  if (!fd) {
    throw DeviceError("gpio peer: cannot open " + path + ": " + base::errno_text(errno));
  }
  return fd;
}

class GpioKernelPeer final : public GpioPeer {
 public:
  GpioKernelPeer(const config::Config& cfg, const dg::GpioSettings& s, const std::string& chip_dir,
                 const std::string& pwm_file)
      : enc_(cfg, s) {
    if (s.max_edge_rate_hz > 0.0) spacing_ns_ = std::llround(2e9 / s.max_edge_rate_hz);
    if (s.line_fault) faults_.allow(PeerFault::kDeviceFault);
    const auto line_file = [&](unsigned line, const char* attr) {
      return chip_dir + "/sim_gpio" + std::to_string(line) + "/" + attr;
    };
    pull_[0] = open_or_throw(line_file(s.line_a, "pull"), O_WRONLY);
    pull_[1] = open_or_throw(line_file(s.line_b, "pull"), O_WRONLY);
    if (s.line_index) pull_[2] = open_or_throw(line_file(*s.line_index, "pull"), O_WRONLY);
    if (s.line_fault) pull_[3] = open_or_throw(line_file(*s.line_fault, "pull"), O_WRONLY);
    direction_ = open_or_throw(line_file(s.line_direction, "value"), O_RDONLY);
    pwm_ = open_or_throw(pwm_file, O_RDONLY);
    timer_.reset(timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
    if (!timer_) throw std::system_error(errno, std::system_category(), "timerfd_create");
    // The wires at rest: every line at the level the encoder's position gives it.
    const std::uint8_t levels = enc_.raw_levels();
    for (int i = 0; i < 4; ++i) {
      if (pull_[i]) put(i, (levels >> i) & 1u);
    }
    next_step_ = base::monotonic_ns() + enc_.period_ns();
    arm(next_step_);
  }

  void service() override {
    std::uint64_t expirations = 0;
    [[maybe_unused]] const ssize_t r = ::read(timer_.get(), &expirations, sizeof expirations);
    std::int64_t now = base::monotonic_ns();
    while (now >= next_step_) {  // the plant follows the wall clock, period by period
      apply_faults(now);
      enc_.apply_output(read_output());
      enc_.step(next_step_);
      next_step_ += enc_.period_ns();
    }
    if (faults_.active(PeerFault::kStopAnswering)) enc_.queue().clear();
    std::optional<std::int64_t> next_edge = put_due_edges();
    felt_.publish(enc_.applied_force(), enc_.output_on());
    enabled_.store(enc_.channel_enabled());
    arm(next_edge ? std::min(*next_edge, next_step_) : next_step_);
  }
  int fd() const noexcept override { return timer_.get(); }
  double applied_force() const noexcept override { return felt_.force(); }
  bool output_on() const noexcept override { return felt_.on(); }
  const Plant& plant() const noexcept override { return enc_.plant(); }

  bool inject(PeerFault f) noexcept override { return faults_.inject(f); }
  bool inject_wire(WireFault f) noexcept override { return wire_faults_.inject(f); }
  bool channel_enabled() const noexcept override { return enabled_.load(); }

 private:
  void put(int line, bool level) {
    const char* text = level ? "pull-up" : "pull-down";
    if (::write(pull_[line].get(), text, std::strlen(text)) < 0) {
      throw std::system_error(errno, std::system_category(), "gpio peer: write pull");
    }
  }

  void arm(std::int64_t at_ns) {
    itimerspec its{};
    its.it_value.tv_sec = static_cast<time_t>(at_ns / 1'000'000'000);
    its.it_value.tv_nsec = static_cast<long>(at_ns % 1'000'000'000);
    timerfd_settime(timer_.get(), TFD_TIMER_ABSTIME, &its, nullptr);
  }

  dg::wire::Output read_output() {
    dg::wire::Output out;
    char buf[256];
    ssize_t n = ::pread(pwm_.get(), buf, sizeof buf - 1, 0);
    if (n < 0) throw std::system_error(errno, std::system_category(), "gpio peer: read PWM");
    buf[n] = '\0';
    unsigned long long period = 0, duty = 0;
    char polarity[16] = {};
    int enabled = 0;
    if (std::sscanf(buf, "period=%llu duty_cycle=%llu polarity=%15s enabled=%d", &period, &duty,
                    polarity, &enabled) == 4) {
      out.period_ns = period;
      out.duty_ns = duty;
      out.pwm_enabled = enabled != 0;
    }
    n = ::pread(direction_.get(), buf, sizeof buf - 1, 0);
    out.direction_level = n > 0 && buf[0] == '1';
    return out;
  }

  void apply_faults(std::int64_t now) {
    if (faults_.take(PeerFault::kDeviceFault)) enc_.set_fault_line(true, now);
    for (WireFault f : {WireFault::kEdgeBurst, WireFault::kIllegalPattern}) {
      if (wire_faults_.take(f)) enc_.inject(f, now);
    }
  }

  // Puts every edge that is due on the wires (paced ones at least spacing_ns_ apart, so a
  // peer that fell behind catches up at a legal rate); the time of the next, if any. An
  // injected pattern put late is shifted, not bunched, and keeps the injected spacing on each
  // line: the kernel reads a gpio-sim line's level in the line's interrupt thread, so two
  // writes on one line closer than that thread's latency (ms in an emulated guest) would reach
  // the driver as one edge, and the pattern would be lost.
  std::optional<std::int64_t> put_due_edges() {
    auto& q = enc_.queue();
    while (!q.empty()) {
      const PendingEdge& p = q.front();
      const auto line = static_cast<std::size_t>(p.line);
      const std::int64_t at =
          p.paced ? std::max(p.due_ns, last_put_ + spacing_ns_)
                  : std::max(p.due_ns + shift_ns_, line_put_[line] + enc_.injected_spacing_ns());
      const std::int64_t now = base::monotonic_ns();
      if (at > now) return at;
      if (!p.paced) shift_ns_ = now - p.due_ns;
      put(static_cast<int>(p.line), p.raw_level);
      last_put_ = line_put_[line] = base::monotonic_ns();
      enc_.sent(p);
      q.pop_front();
    }
    shift_ns_ = 0;  // the pattern is out
    return std::nullopt;
  }

  EncoderSim enc_;
  io::UniqueFd pull_[4];  // A, B, index, fault: indexed by dg::Line
  io::UniqueFd direction_;
  io::UniqueFd pwm_;
  io::UniqueFd timer_;
  std::int64_t next_step_ = 0;
  std::int64_t last_put_ = 0;
  std::int64_t line_put_[4] = {};  // the last put on each line
  std::int64_t spacing_ns_ = 0;
  std::int64_t shift_ns_ = 0;  // how late the injected edges on the wires are
  // Stopped answering, the edges stop while the plant moves: a dead encoder (undetectable).
  // The kernel numbers events itself (no kSkipSequence, no kLoseEdges); the chip is the
  // test's to remove (no kTransportFault).
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering};
  FaultFlags<WireFault> wire_faults_{WireFault::kEdgeBurst, WireFault::kIllegalPattern};
  FeltOutput felt_;
  std::atomic<bool> enabled_{false};
};

}  // namespace

std::unique_ptr<GpioPeer> make_kernel_peer(const config::Config& cfg, const std::string& endpoint) {
  const dg::GpioSettings& s = dg::gpio_settings(cfg);
  check_peer_config(cfg, s);
  const std::size_t comma = endpoint.find(',');
  if (comma == std::string::npos) {
    throw DeviceError("gpio peer: endpoint '" + endpoint +
                      "' is not GPIO_SIM_CHIP_SYSFS_DIR,PWM_SIM_CHANNEL_FILE");
  }
  return std::make_unique<GpioKernelPeer>(cfg, s, endpoint.substr(0, comma),
                                          endpoint.substr(comma + 1));
}

}  // namespace hapticd::sim::gpio
