#include "sim/peers/serial/serial_peer.h"

#include <sys/socket.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <system_error>

#include "drivers/serial/serial_settings.h"
#include "sim/mechanism.h"
#include "sim/peers/peer_state.h"
#include "sim/sim_axis.h"

namespace hapticd::sim::serial {
namespace {

namespace ds = drivers::serial;

class SerialLoopbackPeer final : public LoopbackPeer {
 public:
  SerialLoopbackPeer(const config::Config& cfg, const ds::SerialSettings& s, io::UniqueFd fd)
      : s_(s),
        axis_(cfg.device, cfg.loop.sample_period_s()),
        joints_(s.input.positions.size()),
        scanner_(s_.output.shape),
        fd_(std::move(fd)),
        period_ms_(std::max(1, static_cast<int>(cfg.loop.sample_period_s() * 1e3))) {
    if (joints_ > 1)
      mechanism_ = std::make_unique<Mechanism>(cfg.device, cfg.loop.sample_period_s());
    if (s_.input.status && s_.input.fault_mask != 0) faults_.allow(PeerFault::kDeviceFault);
    if (s_.input.sequence) faults_.allow(PeerFault::kSkipSequence);
  }

  void service() override {
    for (;;) {
      const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
      if (n < 0) {
        if (errno == EAGAIN || errno == EINTR || shut_) break;
        if (errno == ECONNRESET) return;  // the driver closed its end
        throw std::system_error(errno, std::system_category(), "serial peer: recv");
      }
      if (n == 0) return;  // the driver closed its end
      scanner_.push({rx_.data(), static_cast<std::size_t>(n)});
      for (auto f = scanner_.next(); !f.empty(); f = scanner_.next()) handle(f);
    }
    // A stream device speaks on its own while the driver is silent (before enable).
    if (s_.exchange == ds::Exchange::kStream &&
        Clock::now() - last_sent_ >= std::chrono::milliseconds(period_ms_)) {
      answer();
    }
  }
  int fd() const noexcept override { return fd_.get(); }
  int service_interval_ms() const noexcept override {
    return s_.exchange == ds::Exchange::kStream ? period_ms_ : -1;
  }
  double applied_force() const noexcept override { return felt_.force(); }
  bool output_on() const noexcept override { return felt_.on(); }
  const Plant& plant() const noexcept override { return axis_.plant(); }
  const JointPlant* joint_plant() const noexcept override {
    return mechanism_ ? &mechanism_->plant() : nullptr;
  }
  bool inject(PeerFault f) noexcept override {
    if (!faults_.inject(f)) return false;
    if (f == PeerFault::kTransportFault) {  // unplugged: the driver's next read sees end-of-file
      // The socket first: with shut_ set before it, a caller preempted between the two left
      // the peer silent on an open socket, and a loaded test machine saw stale ticks, not the
      // unplug (the conformance suite's serial case).
      ::shutdown(fd_.get(), SHUT_RDWR);
      shut_ = true;
      felt_.vanish();
    }
    return true;
  }

 private:
  using Clock = std::chrono::steady_clock;

  void handle(std::span<const std::uint8_t> frame) {
    ds::OutputValues out;
    ds::decode_output(frame, s_.output, out);
    // A board without an enable switch (Haply's) drives whatever torque it is sent.
    const bool fault = faults_.active(PeerFault::kDeviceFault);
    bool any = false;
    for (std::size_t j = 0; j < joints_; ++j) any = any || out.force[j] != 0.0;
    const bool on = (s_.output.enable ? out.enable : any) && !fault;
    double felt = 0.0;
    if (mechanism_) {
      for (std::size_t j = 0; j < joints_; ++j) {
        const int joint = static_cast<int>(j);
        if (mechanism_->output_on(joint) != on) mechanism_->set_output(joint, on);
        mechanism_->hold_torque(joint, out.force[j]);
        felt = std::max(felt, std::abs(mechanism_->held_torque(joint)));
      }
      mechanism_->step();
    } else {
      if (axis_.output_on() != on) axis_.set_output(on);
      axis_.hold_force(out.force[0]);
      axis_.step();
      felt = axis_.held_force();
    }
    felt_.publish(felt, on);
    answer();
  }

  void answer() {
    if (faults_.active(PeerFault::kStopAnswering) || shut_) return;
    ds::InputValues in;
    for (std::size_t j = 0; j < joints_; ++j) {
      in.position[j] =
          mechanism_ ? mechanism_->encoder_position(static_cast<int>(j)) : axis_.encoder_position();
    }
    sequence_ += faults_.take(PeerFault::kSkipSequence) ? 5 : 1;
    in.sequence = sequence_;
    if (faults_.active(PeerFault::kDeviceFault))
      in.status = s_.input.fault_mask & -s_.input.fault_mask;
    ds::encode_input(in, s_.input, tx_);
    last_sent_ = Clock::now();
    if (::send(fd_.get(), tx_.data(), s_.input.shape.length, MSG_DONTWAIT | MSG_NOSIGNAL) < 0 &&
        errno != EAGAIN && errno != EPIPE && errno != ECONNRESET && !shut_) {
      throw std::system_error(errno, std::system_category(), "serial peer: send");
    }
  }

  const ds::SerialSettings& s_;
  SimAxis axis_;
  std::unique_ptr<Mechanism> mechanism_;
  std::size_t joints_;
  ds::FrameScanner scanner_;
  io::UniqueFd fd_;
  int period_ms_;
  Clock::time_point last_sent_{};
  std::uint32_t sequence_ = 0;
  std::atomic<bool> shut_{false};
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kTransportFault};
  FeltOutput felt_;
  std::array<std::uint8_t, 4 * ds::kMaxFrame> rx_{};
  std::array<std::uint8_t, ds::kMaxFrame> tx_{};
};

}  // namespace

std::unique_ptr<LoopbackPeer> make_loopback_peer(const config::Config& cfg, io::UniqueFd fd) {
  const auto& s = dynamic_cast<const ds::SerialSettings&>(*cfg.device.settings);
  return std::make_unique<SerialLoopbackPeer>(cfg, s, std::move(fd));
}

}  // namespace hapticd::sim::serial
