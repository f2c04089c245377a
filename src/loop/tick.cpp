#include "loop/tick.h"

#include <cmath>

namespace hapticd::loop {
namespace {

// The controller's flags are copied into the tick record unchanged.
constexpr bool same_bit(control::ControlFlag c, telemetry::TickFlag t) {
  return static_cast<std::uint32_t>(c) == static_cast<std::uint32_t>(t);
}
static_assert(same_bit(control::kControlContact, telemetry::kFlagContact));
static_assert(same_bit(control::kControlSaturated, telemetry::kFlagSaturated));
static_assert(same_bit(control::kControlNoPullClamped, telemetry::kFlagNoPullClamped));
static_assert(same_bit(control::kControlUnarmed, telemetry::kFlagUnarmed));
static_assert(same_bit(control::kControlNonFinite, telemetry::kFlagNonFinite));
static_assert(same_bit(control::kControlRunaway, telemetry::kFlagRunaway));

}  // namespace

TickCommand step_tick(control::Controller& law, control::PassivityObserver& observer,
                      const TickInput& in, telemetry::TickRecord& rec) noexcept {
  observer.observe(in.position, in.fresh, in.periods);
  rec.flags |= telemetry::kFlagStepped;
  const control::ControlOutput out = law.step(in.position);
  rec.position = in.position;
  rec.penetration = out.penetration;
  rec.velocity = out.velocity;
  rec.force_computed = out.force_computed;
  rec.flags |= out.flags;
  rec.observer_energy_j = observer.energy_j();
  if (out.flags & control::kControlNonFinite) return {.non_finite = true};
  if (out.flags & control::kControlRunaway) return {.runaway = true};
  const control::Damping d = observer.damp(out.force_commanded, law.law());
  if (d.alpha > 0.0) {
    rec.flags |= telemetry::kFlagPassivityDamped;
    rec.passivity_damping = d.alpha;
    if (d.saturated) rec.flags |= telemetry::kFlagSaturated;
  }
  rec.client_force[0] = in.client_force;
  if (in.client_force == 0.0) return {.command = d.command, .added = d.added};
  // The wall's and the client's force through one saturation, each scaled by its factor.
  const double sum = d.command + in.client_force, limit = law.law().max_force;
  const double scale = std::abs(sum) > limit ? limit / std::abs(sum) : 1.0;
  if (scale < 1.0) rec.flags |= telemetry::kFlagSaturated;
  return {.command = scale * sum, .added = scale * d.added, .client = scale * in.client_force};
}

}  // namespace hapticd::loop
