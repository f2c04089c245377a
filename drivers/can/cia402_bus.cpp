// The CiA 402 drives of one bus (cia402_profile.h): the lifecycle through every node, the tick's
// frames with one SYNC for all of them, and the stop that keeps SYNC going until every node
// has been switched off.
#include <cmath>

#include "base/clock.h"
#include "drivers/can/cia402_profile.h"

namespace hapticd::drivers::can {

std::unique_ptr<CanProfile> make_cia402_profile(const CanSettings& s, double sample_period_s,
                                                int keeper_priority, CanLink& link) {
  return std::make_unique<Cia402Profile>(s, sample_period_s, keeper_priority, link);
}

Cia402Profile::Cia402Profile(const CanSettings& settings, double sample_period_s,
                             int keeper_priority, CanLink& link)
    : settings_(settings),
      period_s_(sample_period_s),
      keeper_priority_(keeper_priority),
      link_(link) {
  nodes_.reserve(settings_.nodes.size());
  for (const CanNode& n : settings_.nodes) nodes_.emplace_back(settings_, n, period_s_, link_);
}

DeviceInfo Cia402Profile::configure() {
  stopped_ = true;
  DeviceInfo info;
  for (Cia402Node& n : nodes_) {
    info.description += (info.description.empty() ? "" : "; ") + n.configure();
  }
  info.joints = nodes_.size();
  info.transport_delay_samples = 1;
  const int hb = settings_.cia402.master_heartbeat_ms;
  master_heartbeat_ticks_ =
      hb == 0 ? 0 : std::max<std::uint32_t>(1, static_cast<std::uint32_t>(hb * 1e-3 / period_s_));
  // A crash: zero torque and the power stage off on every node at one SYNC, then each node
  // pre-operational.
  std::array<CanFrame, 2 * base::kMaxJoints + 1> stop{};
  std::size_t n = 0;
  for (const Cia402Node& node : nodes_) stop[n++] = node.shutdown_frame();
  stop[n++] = canopen::sync_frame();
  for (const Cia402Node& node : nodes_) {
    stop[n++] = canopen::nmt_command(canopen::NmtCommand::kEnterPreOperational, node.node_id());
  }
  link_.set_emergency_frames({stop.data(), n});
  return info;
}

void Cia402Profile::enable() {
  tick_ = 0;
  last_sync_ns_.store(0, std::memory_order_relaxed);
  stopped_ = false;  // from here on a failed enable is undone by the stop, on every node
  for (Cia402Node& n : nodes_) n.enable();
}

// Once per enable (a fault's disable and the close after it are one stop): every node's
// shutdown RPDO, applied at the next SYNC slot (one SYNC per cycle, never two within
// microseconds: a drive's SYNC-locked clock would see a jump); SYNC and hapticd's heartbeat
// kept going while each node is confirmed off and its watches on them switched off; a node
// not confirmed off keeps its watches, whose reaction ends its torque once SYNC stops.
void Cia402Profile::disable(const CanFault&) noexcept {
  if (stopped_) return;
  stopped_ = true;
  if (!link_.is_open()) return;
  for (const Cia402Node& n : nodes_) link_.send_quietly(n.shutdown_frame());
  const auto period_ns = static_cast<std::int64_t>(std::llround(period_s_ * 1e9));
  const std::int64_t last = last_sync_ns_.load(std::memory_order_relaxed);
  std::vector<PeriodicSender::Entry> keep = {
      {canopen::sync_frame(), period_ns, last == 0 ? 0 : last + period_ns}};
  if (master_heartbeat_ticks_ != 0) {
    keep.push_back(
        {canopen::heartbeat_frame(settings_.cia402.master_node_id, canopen::NmtState::kOperational),
         static_cast<std::int64_t>(settings_.cia402.master_heartbeat_ms) * 1'000'000, 0});
  }
  try {
    keeper_.start(link_.fd(), std::move(keep), keeper_priority_);
    keeper_.wait_written(1);
  } catch (...) {
    link_.send_quietly(canopen::sync_frame());  // no thread to be had: the stop at least
  }
  std::array<bool, base::kMaxJoints> off{};
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    off[i] = nodes_[i].confirm_off();
    if (off[i]) nodes_[i].stop_keeping_alive();
  }
  keeper_.stop();
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (off[i]) nodes_[i].confirm_off();  // after the last SYNC: a late RPDO is undone
    nodes_[i].enter_pre_operational();
  }
}

void Cia402Profile::clear_fault() {
  for (Cia402Node& n : nodes_) n.clear_fault();
}

std::vector<std::string> Cia402Profile::notices() const {
  std::vector<std::string> all;
  for (const Cia402Node& n : nodes_) all.insert(all.end(), n.notices().begin(), n.notices().end());
  return all;
}

FrameMeaning Cia402Profile::on_frame(const CanSocket::Received& rx, bool active) noexcept {
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (!nodes_[i].owns(rx.frame)) continue;
    FrameMeaning m = nodes_[i].on_frame(rx, active);
    m.joint = static_cast<std::uint8_t>(i);
    m.fault.joint = m.joint;
    return m;
  }
  link_.count(CanCounter::kUnknownIds);  // late SDO answers too
  return {};
}

void Cia402Profile::sample(std::size_t joint, PositionSample& out) const noexcept {
  nodes_[joint].sample(out);
}

std::span<const CanFrame> Cia402Profile::tick_frames(std::span<const double> forces) noexcept {
  // Every node's RPDO first, then the one SYNC: each drive applies its torque at this SYNC and
  // samples its position.
  std::size_t n = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) tx_[n++] = nodes_[i].rpdo(forces[i]);
  tx_[n++] = canopen::sync_frame();
  if (master_heartbeat_ticks_ != 0 && tick_++ % master_heartbeat_ticks_ == 0) {
    tx_[n++] =
        canopen::heartbeat_frame(settings_.cia402.master_node_id, canopen::NmtState::kOperational);
  }
  last_sync_ns_.store(base::monotonic_ns(), std::memory_order_relaxed);
  return {tx_.data(), n};
}

std::string Cia402Profile::describe(const CanFault& fault, const std::string&) const {
  return nodes_[fault.joint].describe(fault);
}

}  // namespace hapticd::drivers::can
