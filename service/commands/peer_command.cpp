#include "service/commands/peer_command.h"

#include <poll.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <sstream>

#include "gate/number_format.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "sim/joint_plant.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::service {

int peer_command(const PeerOptions& options, SignalWatch& signals) {
  const config::Config cfg = load_config(options.config);
  const wiring::DriverEntry& driver = wiring::find_driver(cfg.device.driver);
  if (driver.peer.make_peer_on == nullptr) {
    throw DeviceError("device.driver '" + cfg.device.driver +
                      "' has no simulated peer for a kernel endpoint");
  }
  check_peer_endpoint(driver.peer, cfg, options.endpoint, options.policy);
  const std::unique_ptr<sim::LoopbackPeer> peer = driver.peer.make_peer_on(cfg, options.endpoint);
  std::string error;
  {
    sim::PeerRunner runner(*peer);
    spdlog::info("peer: a simulated {} device on {}", cfg.device.driver, options.endpoint);
    const auto start = std::chrono::steady_clock::now();
    pollfd fds[2] = {{signals.fd(), POLLIN, 0}, {signals.pipe_fd(), POLLIN, 0}};
    while (!signals.take_pending()) {
      if (options.duration_s &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >=
              *options.duration_s) {
        break;
      }
      poll(fds, 2, 20);
    }
    runner.stop();
    peer->stop();  // a peer's own threads too, before its plant is read
    error = runner.error();
  }
  std::ostringstream os;
  os << "hapticd peer: " << cfg.device.driver << " on " << options.endpoint << ", ";
  if (const sim::JointPlant* joints = peer->joint_plant()) {
    // Several drives moved one mechanism: its joints, and where they put the effector (task
    // coordinates are as many as joints).
    const kinematics::Vec3 x = joints->task_position();
    os << joints->steps() << " periods simulated, final joints";
    for (int i = 0; i < joints->joints(); ++i) {
      os << (i == 0 ? " " : ", ") << gate::format_number(joints->joint_positions()[i]);
    }
    os << ", effector at";
    for (int i = 0; i < kinematics::joint_count(cfg.device.kinematics); ++i) {
      os << (i == 0 ? " " : ", ") << gate::format_number(x[i] * 1e3);
    }
    os << " mm\n";
  } else {
    os << peer->plant().steps() << " periods simulated, final position "
       << gate::format_number(peer->plant().position() * 1e3) << " mm, operator work "
       << gate::format_number(peer->plant().operator_work_j()) << " J\n";
  }
  if (!error.empty()) os << "  failed: " << error << "\n";
  if (!write_stdout(os.str())) return kExitRuntimeFault;
  return error.empty() ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
