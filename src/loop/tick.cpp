#include "loop/tick.h"

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
  if (out.flags & control::kControlNonFinite) return {0.0, 0.0, true, false};
  if (out.flags & control::kControlRunaway) return {0.0, 0.0, false, true};
  const control::Damping d = observer.damp(out.force_commanded, law.law());
  if (d.alpha > 0.0) {
    rec.flags |= telemetry::kFlagPassivityDamped;
    rec.passivity_damping = d.alpha;
    if (d.saturated) rec.flags |= telemetry::kFlagSaturated;
  }
  return {d.command, d.added, false, false};
}

}  // namespace hapticd::loop
