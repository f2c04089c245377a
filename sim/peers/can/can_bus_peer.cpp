#include "sim/peers/can/can_bus_peer.h"

#include <linux/can.h>
#include <sys/socket.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "drivers/can/can_settings.h"
#include "sim/peers/can/can_peer_entry.h"

namespace hapticd::sim {

namespace can = drivers::can;

CanBusPeer::CanBusPeer(const config::Config& cfg, can::CanSocket bus, bool realtime)
    : mechanism_(std::make_unique<Mechanism>(cfg.device, cfg.loop.sample_period_s())),
      bus_(std::move(bus)) {
  const can::CanSettings& s = can::can_settings(cfg);
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    config::Config node = cfg;
    node.device.settings = std::make_shared<can::CanSettings>(can::single_node(s, i));
    auto [bus_end, drive_end] = io::seqpacket_pair();
    drive_fds_.push_back(bus_end.get());
    drive_ends_.push_back(std::move(bus_end));
    drives_.push_back(make_can_drive(node, can::CanSocket::adopt(std::move(drive_end), "bus"),
                                     realtime, {mechanism_.get(), static_cast<int>(i)}));
  }
}

bool CanBusPeer::forward(int from, std::span<const int> to) {
  bool moved = false;
  alignas(8) unsigned char buf[64];
  ssize_t n = 0;
  while ((n = ::recv(from, buf, sizeof buf, MSG_DONTWAIT)) > 0) {
    moved = true;
    if (from == bus_.fd() && n == static_cast<ssize_t>(sizeof(can_frame))) {
      can_frame f{};
      std::memcpy(&f, buf, sizeof f);
      sent_[f.can_id & CAN_SFF_MASK].fetch_add(1, std::memory_order_relaxed);
    }
    // A message the other end cannot take is lost, as on a bus: the master's and the drives'
    // timeouts judge it. A malformed one goes on as it is (the driver counts it).
    for (const int fd : to) {
      [[maybe_unused]] const ssize_t w =
          ::send(fd, buf, static_cast<std::size_t>(n), MSG_DONTWAIT | MSG_NOSIGNAL);
    }
  }
  return moved;
}

void CanBusPeer::service() {
  for (bool moved = true; moved;) {
    moved = forward(bus_.fd(), drive_fds_);
    for (const auto& drive : drives_) drive->service();
    const int bus = bus_.fd();
    for (const int d : drive_fds_) moved = forward(d, std::span<const int>(&bus, 1)) || moved;
  }
}

int CanBusPeer::service_interval_ms() const noexcept {
  return drives_.front()->service_interval_ms();
}

double CanBusPeer::applied_force() const noexcept {
  double largest = 0.0;
  for (const auto& d : drives_) {
    if (std::abs(d->applied_force()) > std::abs(largest)) largest = d->applied_force();
  }
  return largest;
}

bool CanBusPeer::output_on() const noexcept {
  return std::any_of(drives_.begin(), drives_.end(), [](const auto& d) { return d->output_on(); });
}

bool CanBusPeer::inject(PeerFault fault) noexcept {
  bool all = true;
  for (const auto& d : drives_) all = d->inject(fault) && all;
  return all;
}

}  // namespace hapticd::sim
