// GpioLoopbackPeer: the GPIO wires over the driver's socketpair (gpio_peer.h).
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "sim/peers/gpio/gpio_peer.h"
#include "sim/peers/gpio/peer_checks.h"

namespace hapticd::sim::gpio {
namespace {

namespace wire = dg::wire;

class GpioLoopbackPeer final : public GpioPeer {
 public:
  GpioLoopbackPeer(const config::Config& cfg, const dg::GpioSettings& s, io::UniqueFd fd)
      : enc_(cfg, s), owned_(std::move(fd)), fd_(owned_.get()) {
    if (s.max_edge_rate_hz > 0.0) spacing_ns_ = std::llround(2e9 / s.max_edge_rate_hz);
    // Without a fault line the motor driver cannot say it faulted. No sequence of its own
    // (lost edges: WireFault::kLoseEdges).
    for (std::size_t j = s.joints.size(); j-- > 0;) {
      if (!s.joints[j].line_fault) continue;
      fault_lines_ |= 1u << j;
      fault_joint_.store(j);  // the first joint with one, for inject(kDeviceFault)
    }
    if (fault_lines_ != 0) faults_.allow(PeerFault::kDeviceFault);
  }

  // The driver's output messages are the period's clock: the plant steps once per tick, on the
  // last joint's message (the driver writes every joint's in joint order), with the outputs
  // they carry, and the period's edges go back. Nothing moves between messages, however long
  // the driver takes to start or the host holds either thread up.
  void service() override {
    for (;;) {
      const ssize_t n = ::recv(fd_, rx_.data(), rx_.size(), MSG_DONTWAIT);
      if (n < 0) {
        if (errno == EAGAIN || errno == EINTR || shut_) return;
        throw std::system_error(errno, std::system_category(), "gpio peer: recv");
      }
      if (n == 0) return;  // the driver closed its end
      handle({rx_.data(), static_cast<std::size_t>(n)});
      publish();
    }
  }
  int fd() const noexcept override { return fd_; }
  double applied_force() const noexcept override { return felt_.force(); }
  bool output_on() const noexcept override { return felt_.on(); }
  const Plant& plant() const noexcept override { return enc_.plant(); }
  const JointPlant* joint_plant() const noexcept override { return enc_.joint_plant(); }

  bool inject(PeerFault f) noexcept override {
    if (!faults_.inject(f)) return false;
    if (f == PeerFault::kTransportFault) {
      // The wires are cut: the driver's next recv sees it. The socket before the flag, so a
      // caller preempted between the two never leaves the peer silent on an open socket.
      ::shutdown(fd_, SHUT_RDWR);
      shut_ = true;
      // ... and the motor drivers' inputs float to their pull-downs: no drive.
      felt_.vanish();
    }
    return true;
  }
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
  // Each joint's edges: numbered and paced on their own, as each joint's lines would be.
  struct JointWire {
    std::int64_t last_ns = 0;
    std::uint32_t seq = 0;
    std::uint32_t skip = 0;
  };

  // The plant's clock: simulated time, one period per step.
  std::int64_t now_ns() const {
    return 1'000'000'000 + static_cast<std::int64_t>(enc_.steps()) * enc_[0].period_ns();
  }
  std::int64_t period_ns() const { return enc_[0].period_ns(); }

  void send_bytes(const std::uint8_t* p, std::size_t n) {
    if (::send(fd_, p, n, MSG_DONTWAIT | MSG_NOSIGNAL) < 0 && !shut_) {
      // A driver that writes without reading fills the socket: the batch is dropped, as a
      // full kernel event buffer drops events, and the edges' sequence numbers tell the
      // driver how many it lost.
      if (errno == EAGAIN || errno == EPIPE || errno == ECONNRESET) return;
      throw std::system_error(errno, std::system_category(), "gpio peer: send");
    }
  }

  void handle(std::span<const std::uint8_t> msg) {
    wire::Output out;
    if (wire::decode_hello(msg)) {
      std::array<std::uint8_t, wire::kLevelsSize + wire::kMaxJoints - 1> buf{};
      const std::size_t n = wire::encode_levels(enc_.levels(now_ns()), buf);
      send_bytes(buf.data(), n);
    } else if (wire::decode_output(msg, out) && out.joint < enc_.size()) {
      enc_[out.joint].apply_output(out);
      if (out.joint + 1u == enc_.size()) step(now_ns());
    } else {
      ++malformed_;  // a driver that sends garbage: counted, ignored
    }
  }

  // One period from t0: the plant moves under the held outputs, the edges go back.
  void step(std::int64_t t0) {
    if (faults_.take(PeerFault::kDeviceFault)) enc_[fault_joint_.load()].set_fault_line(true, t0);
    const std::size_t target = wire_joint_.load();
    for (WireFault f : {WireFault::kEdgeBurst, WireFault::kIllegalPattern, WireFault::kLoseEdges}) {
      if (!wire_faults_.take(f)) continue;
      if (f == WireFault::kLoseEdges) wires_[target].skip += 5;
      enc_[target].inject(f, t0);
    }
    enc_.step(t0);
    if (faults_.active(PeerFault::kStopAnswering)) {
      // The device went quiet: nothing comes back, not even its clock.
      for (std::size_t j = 0; j < enc_.size(); ++j) enc_[j].queue().clear();
      return;
    }
    send_edges(t0 + period_ns());
  }

  // Joint j's edges due by `until` into batch_, numbered and paced.
  void take_edges(std::size_t j, std::int64_t until) {
    JointWire& w = wires_[j];
    auto& q = enc_[j].queue();
    while (!q.empty()) {
      const PendingEdge& p = q.front();
      const std::int64_t stamp = std::max(p.due_ns, w.last_ns + (p.paced ? spacing_ns_ : 1));
      if (stamp > until) break;
      w.seq += 1 + w.skip;
      w.skip = 0;
      dg::Edge e{stamp, w.seq, p.line, p.raw_level};
      e.joint = static_cast<std::uint8_t>(j);
      batch_.push_back(e);
      enc_[j].sent(p);
      w.last_ns = stamp;
      q.pop_front();
    }
  }

  void send_edges(std::int64_t until) {
    batch_.clear();
    for (std::size_t j = 0; j < enc_.size(); ++j) take_edges(j, until);
    std::array<std::uint8_t, wire::kMaxMessageSize> buf{};
    std::size_t at = 0;
    do {  // at least one message a period: it carries the clock
      const std::size_t n = std::min(batch_.size() - at, wire::kMaxEdgesPerMessage);
      const std::size_t len =
          wire::encode_edges(until, {batch_.data() + at, n}, std::span<std::uint8_t>(buf));
      send_bytes(buf.data(), len);
      at += n;
    } while (at < batch_.size());
  }

  void publish() {
    felt_.publish(enc_.applied_force(), enc_.output_on());  // nothing once the wires are cut
    published_.publish(enc_);
  }

  JointEncoders enc_;
  io::UniqueFd owned_;
  int fd_;
  std::int64_t spacing_ns_ = 0;
  std::array<JointWire, wire::kMaxJoints> wires_{};
  std::uint64_t malformed_ = 0;
  unsigned fault_lines_ = 0;  // bit j: joint j has a fault line
  std::atomic<std::size_t> fault_joint_{0};
  std::atomic<std::size_t> wire_joint_{0};
  std::atomic<bool> shut_{false};
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kTransportFault};
  FaultFlags<WireFault> wire_faults_{WireFault::kEdgeBurst, WireFault::kIllegalPattern,
                                     WireFault::kLoseEdges};
  FeltOutput felt_;
  PublishedJoints published_;
  std::array<std::uint8_t, wire::kMaxMessageSize> rx_{};
  std::vector<dg::Edge> batch_;
};

}  // namespace

std::unique_ptr<GpioPeer> make_loopback_peer(const config::Config& cfg, io::UniqueFd fd) {
  const dg::GpioSettings& s = dg::gpio_settings(cfg);
  check_peer_config(cfg, s);
  return std::make_unique<GpioLoopbackPeer>(cfg, s, std::move(fd));
}

}  // namespace hapticd::sim::gpio
