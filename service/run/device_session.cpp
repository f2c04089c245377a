#include "service/run/device_session.h"

#include "sim/peers/paced_device.h"

namespace hapticd::service {

DeviceSession::DeviceSession(const config::Config& cfg, bool loopback, bool realtime)
    : driver_(wiring::find_driver(cfg.device.driver)) {
  if (!loopback && driver_.make_device != nullptr) {
    device_ = driver_.make_device(cfg);
    return;
  }
  wiring::Loopback pair = driver_.make_loopback(cfg);
  peer_ = std::move(pair.peer);
  // A device answers on its own clock: just below the loop's priority, so it is not starved;
  // and the loop waits for its answers (peer_runner.h: a host may hold any thread up).
  runner_ = std::make_unique<sim::PeerRunner>(*peer_, realtime ? cfg.loop.rt_priority - 1 : 0);
  device_ = std::make_unique<sim::PacedDevice>(std::move(pair.device), *runner_);
}

DeviceSession::~DeviceSession() { shut_down(); }

void DeviceSession::shut_down() noexcept {
  if (device_) device_->close();
  if (!runner_) return;
  runner_->stop();
  try {
    peer_error_ = runner_->error();
  } catch (...) {
    peer_error_ = "the peer failed (and describing it ran out of memory)";
  }
}

std::string DeviceSession::peer_error() const { return peer_error_; }

}  // namespace hapticd::service
