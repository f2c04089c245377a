// ServoLoop's events at a tick boundary: what a live reload, a client's move and a re-arming
// change, taken before the tick reads the device, each marked in the tick log
// (docs/operations.md, the tick log). RT-safe: one atomic load each when nothing is offered.
#include "loop/servo_loop.h"

namespace hapticd::loop {

void ServoLoop::take_reloads(std::uint64_t tick, std::int64_t scheduled_ns,
                             const std::atomic<bool>& stop) noexcept {
  if (options_.law_swap == nullptr && options_.scene_swap == nullptr) return;
  telemetry::TickRecord marker;
  marker.tick = tick;
  marker.scheduled_ns = scheduled_ns;
  bool taken = false;
  if (options_.law_swap != nullptr) {
    if (control::Controller* next = options_.law_swap->take(controller_, tick)) {
      controller_ = next;
      taken = true;
    }
  }
  if (options_.scene_swap != nullptr && options_.scene != nullptr) {
    if (SceneWalls* next = options_.scene_swap->take(options_.scene->walls, tick)) {
      options_.scene->walls = next;
      marker.sequence = telemetry::continues_code(next->continues.data(), next->scene->size());
      taken = true;
    }
  }
  if (taken) {
    counters_[kCounterReloads].add();
    marker.marker = telemetry::kMarkerReloadAccepted;
    log(marker, stop);
  }
  std::uint32_t refused = options_.law_swap ? options_.law_swap->take_refusals() : 0;
  if (options_.scene_swap != nullptr) refused += options_.scene_swap->take_refusals();
  for (; refused > 0; --refused) {
    marker.marker = telemetry::kMarkerReloadRefused;
    log(marker, stop);
  }
}

void ServoLoop::take_moves(std::uint64_t tick, std::int64_t scheduled_ns,
                           const std::atomic<bool>& stop) noexcept {
  if (options_.wall_moves == nullptr || options_.scene == nullptr) return;
  options_.wall_moves->take(tick, [&](std::size_t wall, const kinematics::Vec3& place) {
    options_.scene->walls->scene->move_to(wall, place);
    telemetry::TickRecord marker;
    marker.tick = tick;
    marker.scheduled_ns = scheduled_ns;
    marker.marker = telemetry::kMarkerWallMoved;
    marker.deepest_wall = static_cast<std::uint8_t>(wall);
    for (int a = 0; a < 3; ++a) marker.task_position[a] = place[a];
    log(marker, stop);
  });
}

void ServoLoop::mark_rearmed(const std::atomic<bool>& stop) noexcept {
  telemetry::TickRecord rearmed;
  rearmed.tick = next_tick_;
  rearmed.scheduled_ns = options_.sample.realtime
                             ? 0
                             : static_cast<std::int64_t>(next_tick_) * options_.sample.period_ns;
  rearmed.marker = telemetry::kMarkerRearmed;
  log(rearmed, stop);
}

}  // namespace hapticd::loop
