// RunSession and its clients (docs/clients.md, a client leaving): the walls a client added
// belong to its connection, and go when it does - at the next tick boundary, with no new gate
// (fewer walls only ask less of the device: each wall's verdict stands alone, and the condition
// on walls acting together only gains margin without one) - unless they were added to be kept
// ("keep", or by default with safety.client_walls_on_leave: keep), which belong to no client.
// A client's commanded force goes with it too, at once.
#include <spdlog/spdlog.h>

#include <algorithm>

#include "base/clock.h"
#include "gate/gate_report_format.h"
#include "kinematics/kinematics.h"
#include "service/config_source.h"
#include "service/exit_codes.h"
#include "service/run/gate_derate.h"
#include "service/run/run_session.h"
#include "service/run/scene_edit.h"

namespace hapticd::service {

bool RunSession::holds(std::uint64_t client) const {
  // A stream is held too: its client only reads, and is not idle for that.
  if (stream_ != nullptr && stream_->streaming(client)) return true;
  std::lock_guard lock(mutex_);
  return force_owner_ == client ||
         std::find(owners_.begin(), owners_.end(), client) != owners_.end();
}

nlohmann::json RunSession::servo_cf(const Request& request) {
  const auto refuse = [](const std::string& why) {
    throw ControlRefusal("servo_cf refused: " + why, kExitUsage);
  };
  std::lock_guard lock(mutex_);
  if (!client_force_) refuse("the servo loop is not running yet");
  const double limit = cfg_.safety.client_force_limit;
  if (!(limit > 0.0)) {
    refuse("safety.client_force_limit is 0: this daemon takes no force from its clients");
  }
  const auto m = static_cast<std::size_t>(kinematics::joint_count(cfg_.device.kinematics));
  if (request.force_axes != m) {
    refuse("\"force\": the device has " + std::to_string(m) + " task axes, the force " +
           std::to_string(request.force_axes) + " numbers");
  }
  kinematics::Vec3 f(request.force[0], request.force[1], request.force[2]);
  const double size = f.norm();
  const bool saturated = size > limit;
  if (saturated) f *= limit / size;  // the direction kept, the size said in the answer
  client_force_->offer(f, base::monotonic_ns());
  force_owner_ = f.isZero(0.0) ? 0 : request.client;
  nlohmann::json applied = nlohmann::json::array();
  for (std::size_t a = 0; a < m; ++a) applied.push_back(f[static_cast<int>(a)]);
  return {{"servo_cf",
           {{"force", applied},
            {"saturated", saturated},
            {"limit", limit},
            {"hold_ms", cfg_.safety.client_force_hold_ms}}}};
}

void RunSession::left(std::uint64_t client) {
  if (stream_ != nullptr) stream_->leave(client);
  {
    std::lock_guard lock(mutex_);
    if (client_force_ && force_owner_ == client) {  // never a force from a client that is gone
      client_force_->offer(kinematics::Vec3::Zero(), base::monotonic_ns());
      force_owner_ = 0;
    }
  }
  std::lock_guard serial(reload_mutex_);
  std::vector<std::size_t> gone;
  {
    std::lock_guard lock(mutex_);
    for (std::size_t i = 0; i < owners_.size(); ++i) {
      if (owners_[i] == client) gone.push_back(i);
    }
    if (gone.empty()) return;
  }
  remove_walls(gone, "client " + std::to_string(client) + " left");
}

void RunSession::remove_walls(const std::vector<std::size_t>& gone, const std::string& why) {
  config::Config running;
  Phase phase = Phase::kStarting;
  Prepared next;
  {
    std::lock_guard lock(mutex_);
    running = cfg_;
    phase = phase_;
    next.report = report_;
  }
  if (phase == Phase::kStarting || phase == Phase::kEnded || !scene_.walls ||
      !next.report.workspace) {
    return;
  }
  const EditedScene edited = without_walls(running.effective_yaml, gone);
  // The running configuration less some walls: what was valid stays valid.
  next.cfg = load_config_text_checked(edited.yaml, why, ".", {});
  std::vector<gate::WallVerdict>& verdicts = next.report.workspace->walls;
  std::vector<gate::WallVerdict> kept;
  for (const int from : edited.continues) kept.push_back(verdicts[static_cast<std::size_t>(from)]);
  verdicts = std::move(kept);
  next.law = std::make_unique<control::Controller>(control::make_control_law(next.cfg));
  next.walls = make_scene_walls(next.cfg, session_->device().info(), next.report,
                                scene_.walls.get(), &edited.continues);
  commit(next, phase, why, "scene remove (" + why + ")", &edited.continues, 0);
}

}  // namespace hapticd::service
