#include "sim/peers/evdev/evdev_peer.h"

#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <system_error>

#include "base/clock.h"
#include "config/config_loader.h"

namespace hapticd::sim::evdev {
namespace {

// The kernel's axis values are 32-bit (struct input_absinfo): an encoder whose counts over the
// travel (or per unit) do not fit cannot be an input device, and would wrap, not saturate.
int checked_counts(const config::Config& cfg, double counts, const char* what) {
  if (std::abs(counts) <= std::numeric_limits<std::int32_t>::max()) {
    return static_cast<int>(std::lround(counts));
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", counts);
  throw config::ConfigError({cfg.locate("device.sim.counts_per_unit") +
                             ": device.sim.counts_per_unit: the simulated input device would "
                             "have " +
                             std::string(text) + " counts " + what +
                             ", more than an axis' 32-bit value holds (2147483647)"});
}

}  // namespace

namespace ev = drivers::evdev;
using ev::wire::Message;
using ev::wire::Type;

SocketEvdevPeer::SocketEvdevPeer(const config::Config& cfg, io::UniqueFd fd, int link_delay_samples)
    : settings_(ev::evdev_settings(cfg)),
      fd_(std::move(fd)),
      axis_(cfg.device, cfg.loop.sample_period_s()),
      counts_per_unit_(axis_.counts_per_unit() > 0.0 ? axis_.counts_per_unit() : 1e6),
      fifo_(static_cast<std::size_t>(link_delay_samples) + 1, cfg.device.sim.initial_position) {
  tx_.reserve(ev::wire::kMaxMessage);
  const ev::AxisSettings& a = settings_.axis;
  if (a.scale == ev::Scale::kRange) {
    // The encoder's counts over the configured travel, from 0 at min.
    range_ = {0, checked_counts(cfg, (a.max - a.min) * counts_per_unit_, "over its travel"), 0};
    if (range_.maximum < 0) range_ = {range_.maximum, 0, 0};
  } else {
    const double per_unit = a.rotary ? counts_per_unit_ : counts_per_unit_ * 1e-3;
    range_ = {-(1 << 30), 1 << 30, std::max(1, checked_counts(cfg, per_unit, "per unit"))};
  }
}

std::int32_t SocketEvdevPeer::raw_value(double x) const noexcept {
  const ev::AxisSettings& a = settings_.axis;
  double raw = 0.0;
  if (a.scale == ev::Scale::kRange) {
    const double span = static_cast<double>(range_.maximum) - range_.minimum;
    raw = range_.minimum + (x - a.min) / (a.max - a.min) * span;
  } else {
    raw = (x - a.offset) * (a.rotary ? range_.resolution : range_.resolution * 1e3);
  }
  raw = std::clamp(std::floor(raw), static_cast<double>(range_.minimum),
                   static_cast<double>(range_.maximum));
  return static_cast<std::int32_t>(raw);
}

void SocketEvdevPeer::send(const Message& m) {
  ev::wire::encode(m, tx_);
  if (::send(fd_.get(), tx_.data(), tx_.size(), MSG_DONTWAIT | MSG_NOSIGNAL) < 0 &&
      errno != EPIPE && errno != ECONNRESET && errno != EAGAIN) {
    throw std::system_error(errno, std::system_category(), "evdev peer: send");
  }
}

void SocketEvdevPeer::answer(std::int32_t error, std::int32_t value) {
  Message m;
  m.type = Type::kStatus;
  m.error = error;
  m.b = value;
  send(m);
}

// An update's answer goes where EVIOCSFF's return would: the descriptor the driver handed over.
void SocketEvdevPeer::answer_update(std::int32_t error, std::int32_t value) {
  if (!answers_) return answer(error, value);  // a driver that handed none over
  Message m;
  m.type = Type::kStatus;
  m.error = error;
  m.b = value;
  ev::wire::encode(m, tx_);
  if (::send(answers_.get(), tx_.data(), tx_.size(), MSG_DONTWAIT | MSG_NOSIGNAL) < 0 &&
      errno != EPIPE && errno != ECONNRESET && errno != EAGAIN) {
    throw std::system_error(errno, std::system_category(), "evdev peer: send an answer");
  }
}

void SocketEvdevPeer::send_event(int type, int code, int value) {
  Message m;
  m.type = Type::kEvent;
  m.event = {static_cast<std::uint16_t>(type), static_cast<std::uint16_t>(code), value,
             base::monotonic_ns()};
  send(m);
}

// The force the effect asks for, along the axis: the level's share of full scale, times the
// gain, along the direction as <linux/input.h> encodes it (0x4000 "left", 0xC000 "right": a
// positive level pushes toward -x at 0x4000, -sin(direction)), while it plays.
void SocketEvdevPeer::apply() noexcept {
  double force = 0.0;
  if (playing_.load() && uploaded_) {
    const double along = -std::sin(effect_.direction / 65536.0 * 2.0 * std::numbers::pi);
    force = ev::level_force(effect_.level, settings_.force_full_scale) * gain_ * along;
    if (std::abs(force) < 1e-12) force = 0.0;
  }
  axis_.set_output(playing_.load());
  axis_.hold_force(force);
  applied_.store(force);
}

void SocketEvdevPeer::on_update(const ev::wire::Effect& e) {
  const std::int64_t latency = latency_ns_.load();
  if (latency <= 0 && pending_.empty()) return take_update(e);
  Message m;
  m.type = Type::kUpload;
  m.effect = e;
  pending_.push_back({base::monotonic_ns() + latency, m});
}

void SocketEvdevPeer::take_due() {
  const std::int64_t now = base::monotonic_ns();
  while (!pending_.empty() && pending_.front().due_ns <= now) {
    const Message m = pending_.front().m;
    pending_.pop_front();
    if (m.type == Type::kUpload) {
      take_update(m.effect);
    } else {
      write_ff(m.a, m.b);
    }
  }
}

// An EV_FF event written to the node: play or stop the effect, the gain.
void SocketEvdevPeer::write_ff(int code, int value) {
  if (code == ev::kFfGain) gain_ = value / 65535.0;
  if (uploaded_ && code == effect_.id) playing_.store(value > 0 && fault_.load() == kNoFault);
  apply();
}

int SocketEvdevPeer::service_interval_ms() const noexcept {
  if (pending_.empty()) return -1;
  const std::int64_t left = pending_.front().due_ns - base::monotonic_ns();
  return left <= 0 ? 0 : static_cast<int>((left + 999'999) / 1'000'000);
}

// The update taken: the level applied, the plant stepped, the update answered and the axis
// reported (held by the declared delay; a device slowed on purpose holds nothing more).
void SocketEvdevPeer::take_update(const ev::wire::Effect& e) {
  if (!uploaded_ || e.id != effect_.id) return answer_update(EINVAL, 0);  // erased meanwhile
  if (fault_.load() == kFaultPending) {  // the device stops the effect itself, and says so
    fault_.store(kFaultSaid);
    playing_.store(false);
    send_event(ev::kEvFfStatus, effect_.id, ev::kFfStatusStopped);
  }
  effect_.level = e.level;
  effect_.direction = e.direction;
  apply();
  axis_.step();
  fifo_[fifo_head_] = axis_.encoder_position();
  fifo_head_ = (fifo_head_ + 1) % fifo_.size();
  last_level_.store(e.level);
  updates_taken_.fetch_add(1);
  answer_update(0, e.id);
  if (silent_.load()) return;
  const double x = latency_ns_.load() > 0 ? axis_.encoder_position() : fifo_[fifo_head_];
  send_event(ev::kEvAbs, settings_.axis.code, raw_value(x));
  send_event(ev::kEvSyn, ev::kSynReport, 0);
}

void SocketEvdevPeer::handle(const Message& m) {
  switch (m.type) {
    case Type::kQuery: {
      Message f;
      f.type = Type::kFacts;
      f.facts.name = "hapticd simulated force-feedback device";
      f.facts.bus = 0x06;  // BUS_VIRTUAL
      f.facts.has_axis = m.a == settings_.axis.code;
      f.facts.range = range_;
      f.facts.value = raw_value(fifo_[fifo_head_]);
      f.facts.ff_constant = f.facts.ff_gain = f.facts.ff_autocenter = true;
      f.facts.ff_effects = 1;
      send(f);
      return;
    }
    case Type::kGrab:
      answer(0);
      return;
    case Type::kUpload:
      if (m.effect.id < 0) {
        if (uploaded_) return answer(ENOSPC);  // it holds one effect
        uploaded_ = true;
        effect_ = m.effect;
        effect_.id = 0;
        return answer(0, 0);
      }
      if (!uploaded_ || m.effect.id != effect_.id) return answer_update(EINVAL, 0);
      return on_update(m.effect);
    case Type::kErase:
      if (!uploaded_ || m.a != effect_.id) return answer(EINVAL);
      uploaded_ = false;
      playing_.store(false);
      apply();
      return answer(0);
    case Type::kWriteFf:
      if (!pending_.empty()) return pending_.push_back({0, m});  // behind the update in hand
      return write_ff(m.a, m.b);
    default:
      return;  // a device never receives its own message types
  }
}

void SocketEvdevPeer::lose_host() noexcept {
  playing_.store(false);
  uploaded_ = false;  // closing the node erases the effects of the process that made them
  pending_.clear();
  answers_.reset();  // an update waiting for its answer learns the device is gone
  apply();
}

// One message, and the descriptor passed with it (kAnswers), -1 for none.
void SocketEvdevPeer::receive(std::size_t n, int passed_fd) {
  io::UniqueFd passed(passed_fd);
  const auto m = ev::wire::decode({rx_.data(), n});
  if (!m) return;
  if (m->type == Type::kAnswers) {
    answers_ = std::move(passed);
    return;
  }
  handle(*m);
}

void SocketEvdevPeer::service() {
  take_due();
  while (true) {
    iovec iov{rx_.data(), rx_.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_.get(), &msg, MSG_DONTWAIT | MSG_CMSG_CLOEXEC);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n < 0 && errno == EINTR) continue;
    int passed = -1;
    if (n > 0) {
      const cmsghdr* c = CMSG_FIRSTHDR(&msg);
      if (c != nullptr && c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) {
        std::memcpy(&passed, CMSG_DATA(c), sizeof passed);
      }
    }
    if (n <= 0 || vanished_.load()) {  // the driver closed its end, or the device is gone
      if (passed >= 0) ::close(passed);
      lose_host();
      if (n > 0) continue;  // what was sent to a vanished device is taken off and lost
      return;
    }
    receive(static_cast<std::size_t>(n), passed);
  }
  take_due();
}

bool SocketEvdevPeer::inject(PeerFault fault) noexcept {
  switch (fault) {
    case PeerFault::kStopAnswering:
      silent_.store(true);
      return true;
    case PeerFault::kSkipSequence:
      return false;
    case PeerFault::kDeviceFault:
      fault_.store(kFaultPending);  // said with the answer to the next update
      return true;
    case PeerFault::kTransportFault:
      vanished_.store(true);
      playing_.store(false);
      applied_.store(0.0);
      ::shutdown(fd_.get(), SHUT_RDWR);
      return true;
  }
  return false;
}

}  // namespace hapticd::sim::evdev
