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
#include <utility>
#include <vector>

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

// One joint's wires: its lines' pull attributes, its direction line, its PWM channel's file.
struct JointWires {
  io::UniqueFd pull[4];  // A, B, index, fault: indexed by dg::Line
  io::UniqueFd direction;
  io::UniqueFd pwm;
  std::int64_t last_put = 0;
  std::int64_t line_put[4] = {};  // the last put on each line
  std::int64_t shift_ns = 0;      // how late the injected edges on the wires are
};

// "CHIP_DIR,PWM_FILE" per joint, ';' between joints.
std::vector<std::pair<std::string, std::string>> split_endpoint(const std::string& endpoint) {
  std::vector<std::pair<std::string, std::string>> out;
  std::size_t at = 0;
  for (;;) {
    const std::size_t end = endpoint.find(';', at);
    const std::string one = endpoint.substr(at, end == std::string::npos ? end : end - at);
    const std::size_t comma = one.find(',');
    if (comma == std::string::npos) {
      throw DeviceError("gpio peer: endpoint '" + endpoint +
                        "' is not GPIO_SIM_CHIP_SYSFS_DIR,PWM_SIM_CHANNEL_FILE (one pair per "
                        "joint, ';' between them)");
    }
    out.emplace_back(one.substr(0, comma), one.substr(comma + 1));
    if (end == std::string::npos) return out;
    at = end + 1;
  }
}

class GpioKernelPeer final : public GpioPeer {
 public:
  GpioKernelPeer(const config::Config& cfg, const dg::GpioSettings& s,
                 const std::vector<std::pair<std::string, std::string>>& ends)
      : enc_(cfg, s) {
    if (s.max_edge_rate_hz > 0.0) spacing_ns_ = std::llround(2e9 / s.max_edge_rate_hz);
    for (std::size_t j = 0; j < s.joints.size(); ++j) open_joint(s.joint(j), ends[j], wires_[j]);
    for (std::size_t j = s.joints.size(); j-- > 0;) {
      if (!s.joints[j].line_fault) continue;
      fault_lines_ |= 1u << j;
      fault_joint_.store(j);
    }
    if (fault_lines_ != 0) faults_.allow(PeerFault::kDeviceFault);
    timer_.reset(timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
    if (!timer_) throw std::system_error(errno, std::system_category(), "timerfd_create");
    // The wires at rest: every line at the level the encoder's position gives it.
    for (std::size_t j = 0; j < enc_.size(); ++j) {
      const std::uint8_t levels = enc_[j].raw_levels();
      for (int i = 0; i < 4; ++i) {
        if (wires_[j].pull[i]) put(wires_[j], i, (levels >> i) & 1u);
      }
    }
    next_step_ = base::monotonic_ns() + enc_[0].period_ns();
    arm(next_step_);
  }

  void service() override {
    std::uint64_t expirations = 0;
    [[maybe_unused]] const ssize_t r = ::read(timer_.get(), &expirations, sizeof expirations);
    std::int64_t now = base::monotonic_ns();
    while (now >= next_step_) {  // the plant follows the wall clock, period by period
      apply_faults(now);
      for (std::size_t j = 0; j < enc_.size(); ++j) enc_[j].apply_output(read_output(wires_[j]));
      enc_.step(next_step_);
      next_step_ += enc_[0].period_ns();
    }
    std::optional<std::int64_t> next_edge;
    for (std::size_t j = 0; j < enc_.size(); ++j) {
      if (faults_.active(PeerFault::kStopAnswering)) enc_[j].queue().clear();
      const std::optional<std::int64_t> t = put_due_edges(j);
      if (t && (!next_edge || *t < *next_edge)) next_edge = t;
    }
    felt_.publish(enc_.applied_force(), enc_.output_on());
    published_.publish(enc_);
    arm(next_edge ? std::min(*next_edge, next_step_) : next_step_);
  }
  int fd() const noexcept override { return timer_.get(); }
  double applied_force() const noexcept override { return felt_.force(); }
  bool output_on() const noexcept override { return felt_.on(); }
  const Plant& plant() const noexcept override { return enc_.plant(); }
  const JointPlant* joint_plant() const noexcept override { return enc_.joint_plant(); }

  bool inject(PeerFault f) noexcept override { return faults_.inject(f); }
  bool inject_fault_line(std::size_t joint) noexcept override {
    if (joint >= enc_.size() || (fault_lines_ & (1u << joint)) == 0) return false;
    fault_joint_.store(joint);
    return faults_.inject(PeerFault::kDeviceFault);
  }
  bool inject_wire(WireFault f, std::size_t joint) noexcept override {
    if (joint >= enc_.size()) return false;
    wire_joint_.store(joint);
    return wire_faults_.inject(f);
  }
  bool channel_enabled() const noexcept override { return published_.channel_enabled(); }
  std::uint64_t duty_ns(std::size_t joint) const noexcept override {
    return published_.duty_ns(joint);
  }

 private:
  static void open_joint(const dg::GpioJointSettings& j,
                         const std::pair<std::string, std::string>& end, JointWires& w) {
    const auto line_file = [&](unsigned line, const char* attr) {
      return end.first + "/sim_gpio" + std::to_string(line) + "/" + attr;
    };
    w.pull[0] = open_or_throw(line_file(j.line_a, "pull"), O_WRONLY);
    w.pull[1] = open_or_throw(line_file(j.line_b, "pull"), O_WRONLY);
    if (j.line_index) w.pull[2] = open_or_throw(line_file(*j.line_index, "pull"), O_WRONLY);
    if (j.line_fault) w.pull[3] = open_or_throw(line_file(*j.line_fault, "pull"), O_WRONLY);
    w.direction = open_or_throw(line_file(j.line_direction, "value"), O_RDONLY);
    w.pwm = open_or_throw(end.second, O_RDONLY);
  }

  static void put(JointWires& w, int line, bool level) {
    const char* text = level ? "pull-up" : "pull-down";
    if (::write(w.pull[line].get(), text, std::strlen(text)) < 0) {
      throw std::system_error(errno, std::system_category(), "gpio peer: write pull");
    }
  }

  void arm(std::int64_t at_ns) {
    itimerspec its{};
    its.it_value.tv_sec = static_cast<time_t>(at_ns / 1'000'000'000);
    its.it_value.tv_nsec = static_cast<long>(at_ns % 1'000'000'000);
    timerfd_settime(timer_.get(), TFD_TIMER_ABSTIME, &its, nullptr);
  }

  static dg::wire::Output read_output(JointWires& w) {
    dg::wire::Output out;
    char buf[256];
    ssize_t n = ::pread(w.pwm.get(), buf, sizeof buf - 1, 0);
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
    n = ::pread(w.direction.get(), buf, sizeof buf - 1, 0);
    out.direction_level = n > 0 && buf[0] == '1';
    return out;
  }

  void apply_faults(std::int64_t now) {
    if (faults_.take(PeerFault::kDeviceFault)) enc_[fault_joint_.load()].set_fault_line(true, now);
    for (WireFault f : {WireFault::kEdgeBurst, WireFault::kIllegalPattern}) {
      if (wire_faults_.take(f)) enc_[wire_joint_.load()].inject(f, now);
    }
  }

  // Puts every edge of joint j that is due on its wires (paced ones at least spacing_ns_ apart,
  // so a peer that fell behind catches up at a legal rate); the time of the next, if any. An
  // injected pattern put late is shifted, not bunched, and keeps the injected spacing on each
  // line: the kernel reads a gpio-sim line's level in the line's interrupt thread, so two
  // writes on one line closer than that thread's latency (ms in an emulated guest) would reach
  // the driver as one edge, and the pattern would be lost.
  std::optional<std::int64_t> put_due_edges(std::size_t j) {
    JointWires& w = wires_[j];
    auto& q = enc_[j].queue();
    while (!q.empty()) {
      const PendingEdge& p = q.front();
      const auto line = static_cast<std::size_t>(p.line);
      const std::int64_t at = p.paced ? std::max(p.due_ns, w.last_put + spacing_ns_)
                                      : std::max(p.due_ns + w.shift_ns,
                                                 w.line_put[line] + enc_[j].injected_spacing_ns());
      const std::int64_t now = base::monotonic_ns();
      if (at > now) return at;
      if (!p.paced) w.shift_ns = now - p.due_ns;
      put(w, static_cast<int>(p.line), p.raw_level);
      w.last_put = w.line_put[line] = base::monotonic_ns();
      enc_[j].sent(p);
      q.pop_front();
    }
    w.shift_ns = 0;  // the pattern is out
    return std::nullopt;
  }

  JointEncoders enc_;
  std::array<JointWires, dg::wire::kMaxJoints> wires_;
  io::UniqueFd timer_;
  std::int64_t next_step_ = 0;
  std::int64_t spacing_ns_ = 0;
  unsigned fault_lines_ = 0;  // bit j: joint j has a fault line
  std::atomic<std::size_t> fault_joint_{0};
  std::atomic<std::size_t> wire_joint_{0};
  // Stopped answering, the edges stop while the plant moves: a dead encoder (undetectable).
  // The kernel numbers events itself (no kSkipSequence, no kLoseEdges); the chip is the
  // test's to remove (no kTransportFault).
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering};
  FaultFlags<WireFault> wire_faults_{WireFault::kEdgeBurst, WireFault::kIllegalPattern};
  FeltOutput felt_;
  PublishedJoints published_;
};

}  // namespace

std::unique_ptr<GpioPeer> make_kernel_peer(const config::Config& cfg, const std::string& endpoint) {
  const dg::GpioSettings& s = dg::gpio_settings(cfg);
  check_peer_config(cfg, s);
  const auto ends = split_endpoint(endpoint);
  if (ends.size() != s.joints.size()) {
    throw DeviceError("gpio peer: endpoint '" + endpoint + "' names " +
                      std::to_string(ends.size()) + " joint(s)' wires, the configuration has " +
                      std::to_string(s.joints.size()) + " (one CHIP_DIR,PWM_FILE pair per joint)");
  }
  return std::make_unique<GpioKernelPeer>(cfg, s, ends);
}

}  // namespace hapticd::sim::gpio
