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

namespace {

// Where the simulated axes start: device.sim.initial_position, or the mechanism's origin.
std::array<double, 2> evdev_start_of(const config::Config& cfg, const Mechanism* m) {
  if (m == nullptr) return {cfg.device.sim.initial_position, 0.0};
  const kinematics::Vec3& q = m->plant().joint_positions();
  return {q[0], q[1]};
}

}  // namespace

SocketEvdevPeer::SocketEvdevPeer(const config::Config& cfg, io::UniqueFd fd, int link_delay_samples)
    : settings_(ev::evdev_settings(cfg)),
      joints_(settings_.joints),
      effects_held_(joints_ == 2 && settings_.effect == ev::EffectMode::kPerAxis ? 2 : 1),
      fd_(std::move(fd)),
      axis_(cfg.device, cfg.loop.sample_period_s()),
      mechanism_(joints_ == 2 ? std::make_unique<Mechanism>(cfg.device, cfg.loop.sample_period_s())
                              : nullptr),
      counts_per_unit_(axis_.counts_per_unit() > 0.0 ? axis_.counts_per_unit() : 1e6),
      fifo_(static_cast<std::size_t>(link_delay_samples) + 1,
            evdev_start_of(cfg, mechanism_.get())) {
  tx_.reserve(ev::wire::kMaxMessage);
  for (int j = 0; j < joints_; ++j) {
    const ev::AxisSettings& a = settings_.axis_of(j);
    ev::AxisRange& r = range_[static_cast<std::size_t>(j)];
    if (a.scale == ev::Scale::kRange) {
      // The encoder's counts over the configured travel, from 0 at min.
      r = {0, checked_counts(cfg, (a.max - a.min) * counts_per_unit_, "over its travel"), 0};
      if (r.maximum < 0) r = {r.maximum, 0, 0};
    } else {
      const double per_unit = a.rotary ? counts_per_unit_ : counts_per_unit_ * 1e-3;
      r = {-(1 << 30), 1 << 30, std::max(1, checked_counts(cfg, per_unit, "per unit"))};
    }
  }
}

std::int32_t SocketEvdevPeer::raw_value(int j, double x) const noexcept {
  const ev::AxisSettings& a = settings_.axis_of(j);
  const ev::AxisRange& r = range_[static_cast<std::size_t>(j)];
  double raw = 0.0;
  if (a.scale == ev::Scale::kRange) {
    const double span = static_cast<double>(r.maximum) - r.minimum;
    raw = r.minimum + (x - a.min) / (a.max - a.min) * span;
  } else {
    raw = (x - a.offset) * (a.rotary ? r.resolution : r.resolution * 1e3);
  }
  raw = std::clamp(std::floor(raw), static_cast<double>(r.minimum), static_cast<double>(r.maximum));
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

// The force the effects ask for on each joint, while they play: each level's share of full
// scale, times the gain, along its direction as <linux/input.h> encodes it (0x4000 "left",
// 0xC000 "right", 0x0000 "down", 0x8000 "up": ev::plane_force), the joint's axis being the
// effect's x or y as its direction_deg lies (one axis: x). Summed over the effects, as
// ff-memless combines them.
void SocketEvdevPeer::apply() noexcept {
  std::array<double, kAxes> force{};
  for (int k = 0; k < effects_held_; ++k) {
    if (!playing_.load() || !uploaded_[k] || !effect_playing_[k]) continue;
    for (int j = 0; j < joints_; ++j) {
      force[j] += ev::plane_force(j, effects_[k].direction, effects_[k].level, settings_) * gain_;
    }
  }
  double largest = 0.0;
  for (int j = 0; j < joints_; ++j) {
    if (std::abs(force[j]) < 1e-12) force[j] = 0.0;
    if (std::abs(force[j]) > std::abs(largest)) largest = force[j];
    joint_force_[j].store(force[j]);
    if (mechanism_) {
      mechanism_->set_output(j, playing_.load());
      mechanism_->hold_torque(j, force[j]);
    }
  }
  axis_.set_output(playing_.load());
  axis_.hold_force(force[0]);
  applied_.store(largest);
}

int SocketEvdevPeer::effect_index(int id) const noexcept {
  for (int k = 0; k < effects_held_; ++k) {
    if (uploaded_[k] && effects_[k].id == id) return k;
  }
  return -1;
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

// An EV_FF event written to the node: play or stop an effect, the gain.
void SocketEvdevPeer::write_ff(int code, int value) {
  if (code == ev::kFfGain) gain_ = value / 65535.0;
  if (const int k = effect_index(code); k >= 0) {
    effect_playing_[k] = value > 0 && fault_.load() == kNoFault;
    bool any = false;
    for (int i = 0; i < effects_held_; ++i) any = any || (uploaded_[i] && effect_playing_[i]);
    playing_.store(any);
  }
  apply();
}

int SocketEvdevPeer::service_interval_ms() const noexcept {
  if (pending_.empty()) return -1;
  const std::int64_t left = pending_.front().due_ns - base::monotonic_ns();
  return left <= 0 ? 0 : static_cast<int>((left + 999'999) / 1'000'000);
}

// The update taken: the level applied and answered; at the tick's last effect (effects[1] with
// effect: per_axis, the update thread's order) the plant stepped and the axes reported.
void SocketEvdevPeer::take_update(const ev::wire::Effect& e) {
  const int k = effect_index(e.id);
  if (k < 0) return answer_update(EINVAL, 0);  // erased meanwhile
  if (fault_.load() == kFaultPending) {        // the device stops its effects itself, and says so
    fault_.store(kFaultSaid);
    playing_.store(false);
    effect_playing_.fill(false);
    send_event(ev::kEvFfStatus, e.id, ev::kFfStatusStopped);
  }
  effects_[k].level = e.level;
  effects_[k].direction = e.direction;
  apply();
  last_level_.store(e.level);
  updates_taken_.fetch_add(1);
  if (k + 1 < effects_held_) return answer_update(0, e.id);
  step_and_report();
  answer_update(0, e.id);
  if (silent_.load()) return;
  const bool late = latency_ns_.load() > 0;
  for (int j = 0; j < joints_; ++j) {
    const double x = late
                         ? (mechanism_ ? mechanism_->encoder_position(j) : axis_.encoder_position())
                         : fifo_[fifo_head_][j];
    send_event(ev::kEvAbs, settings_.axis_of(j).code, raw_value(j, x));
  }
  send_event(ev::kEvSyn, ev::kSynReport, 0);
}

// One period of the plant (or the mechanism), its encoders into the delay line (held by the
// declared delay; a device slowed on purpose holds nothing more).
void SocketEvdevPeer::step_and_report() {
  std::array<double, kAxes>& slot = fifo_[fifo_head_];
  if (mechanism_) {
    mechanism_->step();
    for (int j = 0; j < joints_; ++j) slot[j] = mechanism_->encoder_position(j);
  } else {
    axis_.step();
    slot[0] = axis_.encoder_position();
  }
  fifo_head_ = (fifo_head_ + 1) % fifo_.size();
}

void SocketEvdevPeer::query(const Message& m) {
  Message f;
  f.type = Type::kFacts;
  f.facts.name = "hapticd simulated force-feedback device";
  f.facts.bus = 0x06;  // BUS_VIRTUAL
  for (int j = 0; j < joints_; ++j) {
    if (m.a != settings_.axis_of(j).code) continue;
    f.facts.has_axis = true;
    f.facts.range = range_[static_cast<std::size_t>(j)];
    f.facts.value = raw_value(j, fifo_[fifo_head_][j]);
  }
  f.facts.ff_constant = f.facts.ff_gain = f.facts.ff_autocenter = true;
  f.facts.ff_effects = effects_held_;
  send(f);
}

// EVIOCSFF: a new effect (id -1) takes the next free slot, an existing one is an update.
void SocketEvdevPeer::upload(const Message& m) {
  if (m.effect.id >= 0) {
    if (effect_index(m.effect.id) < 0) return answer_update(EINVAL, 0);
    return on_update(m.effect);
  }
  for (int k = 0; k < effects_held_; ++k) {
    if (uploaded_[k]) continue;
    uploaded_[k] = true;
    effect_playing_[k] = false;
    effects_[k] = m.effect;
    effects_[k].id = static_cast<std::int16_t>(k);
    return answer(0, k);
  }
  answer(ENOSPC);  // it holds effects_held_ effects
}

void SocketEvdevPeer::handle(const Message& m) {
  switch (m.type) {
    case Type::kQuery:
      return query(m);
    case Type::kGrab:
      answer(0);
      return;
    case Type::kUpload:
      return upload(m);
    case Type::kErase: {
      const int k = effect_index(m.a);
      if (k < 0) return answer(EINVAL);
      uploaded_[k] = false;
      effect_playing_[k] = false;
      playing_.store(
          std::any_of(effect_playing_.begin(), effect_playing_.end(), [](bool p) { return p; }));
      apply();
      return answer(0);
    }
    case Type::kWriteFf:
      if (!pending_.empty()) return pending_.push_back({0, m});  // behind the update in hand
      return write_ff(m.a, m.b);
    default:
      return;  // a device never receives its own message types
  }
}

void SocketEvdevPeer::lose_host() noexcept {
  playing_.store(false);
  uploaded_.fill(false);  // closing the node erases the effects of the process that made them
  effect_playing_.fill(false);
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
      for (std::atomic<double>& f : joint_force_) f.store(0.0);
      ::shutdown(fd_.get(), SHUT_RDWR);
      return true;
  }
  return false;
}

}  // namespace hapticd::sim::evdev
