#include "loop/state_publish.h"

namespace hapticd::loop {

void StatePublisher::publish(const telemetry::TickRecord& rec, std::uint32_t periods,
                             std::int64_t wake_ns, const kinematics::Vec3& force) noexcept {
  if (block_ == nullptr) return;
  client::StateSample s;
  s.tick = rec.tick;
  s.time_ns = wake_ns;
  const bool several = rec.joints > 1;
  const double q[] = {rec.position, rec.joint_position[0], rec.joint_position[1]};
  const double tau[] = {rec.force_commanded, rec.joint_force[0], rec.joint_force[1]};
  for (int i = 0; i < 3; ++i) {
    s.q[i] = q[i];
    s.effort[i] = tau[i];
    s.x[i] = several ? rec.task_position[i] : (i == 0 ? rec.position : 0.0);
    s.f[i] = force[i];
  }
  // A tick without a new position (stale, held, none yet) keeps the last velocity.
  const bool fresh =
      (rec.flags & (telemetry::kFlagStale | telemetry::kFlagHeld | telemetry::kFlagNoPosition)) ==
      0;
  const double per_s = rate_hz_ / (periods > 0 ? periods : 1);  // one division a tick
  for (int i = 0; i < 3; ++i) {
    s.qd[i] = !previous_ ? 0.0 : fresh ? (s.q[i] - last_.q[i]) * per_s : last_.qd[i];
    s.v[i] = !previous_ ? 0.0 : fresh ? (s.x[i] - last_.x[i]) * per_s : last_.v[i];
  }
  s.observer_energy_j = rec.observer_energy_j;
  s.flags = rec.flags;
  s.wall_contact = several ? rec.wall_contact : (rec.flags & telemetry::kFlagContact ? 1u : 0u);
  s.fault_cause = rec.fault_cause;
  previous_ = previous_ || fresh;
  last_ = s;
  block_->publish(s);
}

}  // namespace hapticd::loop
