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
    if (s.line_fault) faults_.allow(PeerFault::kDeviceFault);
  }

  // The driver's output message is the period's clock: the plant steps once per message, with
  // the output it carries, and the period's edges go back. Nothing moves between messages,
  // however long the driver takes to start or the host holds either thread up.
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

  bool inject(PeerFault f) noexcept override {
    if (!faults_.inject(f)) return false;
    if (f == PeerFault::kTransportFault) {
      shut_ = true;
      ::shutdown(fd_, SHUT_RDWR);  // the wires are cut: the driver's next recv sees it
      // ... and the motor driver's inputs float to their pull-downs: no drive.
      felt_.vanish();
    }
    return true;
  }
  bool inject_wire(WireFault f) noexcept override { return wire_faults_.inject(f); }
  bool channel_enabled() const noexcept override { return enabled_.load(); }

 private:
  // The plant's clock: simulated time, one period per step.
  std::int64_t now_ns() const {
    return 1'000'000'000 + static_cast<std::int64_t>(enc_.plant().steps()) * enc_.period_ns();
  }

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
      std::array<std::uint8_t, wire::kLevelsSize> buf{};
      wire::encode_levels({enc_.raw_levels(), now_ns()}, buf);
      send_bytes(buf.data(), buf.size());
    } else if (wire::decode_output(msg, out)) {
      enc_.apply_output(out);
      step(now_ns());
    } else {
      ++malformed_;  // a driver that sends garbage: counted, ignored
    }
  }

  // One period from t0: the plant moves under the held output, the edges go back.
  void step(std::int64_t t0) {
    if (faults_.take(PeerFault::kDeviceFault)) enc_.set_fault_line(true, t0);
    for (WireFault f : {WireFault::kEdgeBurst, WireFault::kIllegalPattern, WireFault::kLoseEdges}) {
      if (!wire_faults_.take(f)) continue;
      if (f == WireFault::kLoseEdges) skip_ += 5;
      enc_.inject(f, t0);
    }
    enc_.step(t0);
    if (faults_.active(PeerFault::kStopAnswering)) {
      enc_.queue().clear();  // the device went quiet: nothing comes back, not even its clock
      return;
    }
    send_edges(t0 + enc_.period_ns());
  }

  void send_edges(std::int64_t until) {
    std::vector<dg::Edge>& batch = batch_;
    batch.clear();
    auto& q = enc_.queue();
    while (!q.empty()) {
      const PendingEdge& p = q.front();
      const std::int64_t stamp = std::max(p.due_ns, last_ns_ + (p.paced ? spacing_ns_ : 1));
      if (stamp > until) break;
      seq_ += 1 + skip_;
      skip_ = 0;
      batch.push_back({stamp, seq_, p.line, p.raw_level});
      enc_.sent(p);
      last_ns_ = stamp;
      q.pop_front();
    }
    std::array<std::uint8_t, wire::kMaxMessageSize> buf{};
    std::size_t at = 0;
    do {  // at least one message a period: it carries the clock
      const std::size_t n = std::min(batch.size() - at, wire::kMaxEdgesPerMessage);
      const std::size_t len =
          wire::encode_edges(until, {batch.data() + at, n}, std::span<std::uint8_t>(buf));
      send_bytes(buf.data(), len);
      at += n;
    } while (at < batch.size());
  }

  void publish() {
    felt_.publish(enc_.applied_force(), enc_.output_on());  // nothing once the wires are cut
    enabled_.store(enc_.channel_enabled());
  }

  EncoderSim enc_;
  io::UniqueFd owned_;
  int fd_;
  std::int64_t spacing_ns_ = 0;
  std::int64_t last_ns_ = 0;
  std::uint32_t seq_ = 0;
  std::uint32_t skip_ = 0;
  std::uint64_t malformed_ = 0;
  std::atomic<bool> shut_{false};
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kTransportFault};
  FaultFlags<WireFault> wire_faults_{WireFault::kEdgeBurst, WireFault::kIllegalPattern,
                                     WireFault::kLoseEdges};
  FeltOutput felt_;
  std::atomic<bool> enabled_{false};
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
