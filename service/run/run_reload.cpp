// RunSession's live reload (the control socket's reload and scene requests, SIGHUP): parsed,
// checked, gated and built off the RT thread, then offered to it and taken at a tick boundary
// (docs/operations.md, the control socket).
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>

#include "config/config_loader.h"
#include "gate/gate_report_format.h"
#include "gate/number_format.h"
#include "kinematics/kinematics.h"
#include "service/config_source.h"
#include "service/exit_codes.h"
#include "service/run/gate_derate.h"
#include "service/run/reload_check.h"
#include "service/run/run_session.h"
#include "service/run/scene_edit.h"

namespace hapticd::service {
namespace {

using nlohmann::json;

// How long a reload waits for the running loop to take the new law: the loop takes it at its
// next tick, so only an RT thread starved for this long fails to (then the reload is refused).
constexpr std::chrono::milliseconds kSwapTimeout{10000};

// A point as YAML's flow sequence, every digit kept.
std::string point_yaml(const kinematics::Vec3& x, std::size_t m) {
  std::string s = "[";
  for (std::size_t a = 0; a < m; ++a) {
    s += (a ? ", " : "") + gate::format_number(x[static_cast<int>(a)], 17);
  }
  return s + "]";
}

// A move's point within reach: inside the workspace box grown by its own extent each way (a
// wall further out covers all of it or none of it). ControlRefusal (code 2) otherwise.
void check_in_reach(const kinematics::Kinematics& k, const kinematics::Vec3& x, std::size_t m) {
  const kinematics::Box& box = kinematics::workspace(k);
  for (std::size_t a = 0; a < m; ++a) {
    const int i = static_cast<int>(a);
    const double extent = box.upper[i] - box.lower[i];
    if (!std::isfinite(extent)) continue;  // an unbounded workspace (cartesian, joints)
    if (x[i] >= box.lower[i] - extent && x[i] <= box.upper[i] + extent) continue;
    throw ControlRefusal(
        "scene move refused: \"point\"[" + std::to_string(a) + "]: " + gate::format_number(x[i]) +
            " m is out of reach: the workspace is " + gate::format_number(box.lower[i]) + " to " +
            gate::format_number(box.upper[i]) +
            " m along it, and a wall's point may lie at most its extent beyond",
        kExitUsage);
  }
}

}  // namespace

// Parsed, checked, gated and built off the RT thread; swapped in at a tick boundary.
json RunSession::reload(const std::string& text, const std::string& source,
                        const std::vector<std::string>& sets) {
  std::lock_guard serial(reload_mutex_);
  return {{"reload", apply(text, source, sets, "reload", nullptr)}};
}

json RunSession::scene(const SceneEdit& edit, std::uint64_t client) {
  if (edit.op == SceneEdit::Op::kMove) return move(edit);
  std::lock_guard serial(reload_mutex_);
  const std::string what = std::string("scene ") + scene_op_name(edit.op);
  std::string document;
  {
    std::lock_guard lock(mutex_);
    document = cfg_.effective_yaml;
  }
  if (!scene_.walls) {
    throw ControlRefusal(what +
                             " refused: scene requests change the walls of a device of "
                             "several joints (walls:); a device of one joint reloads its wall",
                         kExitUsage);
  }
  EditedScene edited;
  try {
    edited = edit_walls(document, edit);
  } catch (const ControlRefusal& e) {
    throw ControlRefusal(what + " refused: " + e.what(), e.code());
  }
  bool keep = false;
  {
    std::lock_guard lock(mutex_);
    keep = edit.keep.value_or(cfg_.safety.client_walls_on_leave == config::ClientWalls::kKeep);
  }
  json out = apply(edited.yaml, "scene request", {}, what, &edited.continues, keep ? 0 : client);
  out["op"] = scene_op_name(edit.op);
  out["index"] = edited.index;
  out["walls"] = edited.continues.size();
  return {{"scene", out}};
}

// Checked here, then handed to the loop: the gate proved the walls passive wherever they move,
// and the loop slides each no faster than safety.max_wall_speed.
json RunSession::move(const SceneEdit& edit) {
  std::lock_guard serial(reload_mutex_);
  const auto refuse = [&](const std::string& why, int code) {
    throw ControlRefusal("scene move refused: " + why, code);
  };
  if (!scene_.walls) {
    refuse("scene requests move the walls of a device of several joints (walls:)", kExitUsage);
  }
  std::string not_movable;
  config::Config running;
  Phase phase = Phase::kStarting;
  {
    std::lock_guard lock(mutex_);
    not_movable = why_not_movable(report_);
    running = cfg_;
    phase = phase_;
  }
  const std::size_t walls = running.walls.size();
  if (edit.index >= walls) {
    refuse("\"index\": " + std::to_string(edit.index) + " names no wall (" + std::to_string(walls) +
               " walls)",
           kExitUsage);
  }
  const kinematics::Kinematics& k = running.device.kinematics;
  const auto m = static_cast<std::size_t>(kinematics::joint_count(k));
  if (edit.axes != m) {
    refuse("\"point\": the device has " + std::to_string(m) + " task axes, the point " +
               std::to_string(edit.axes) + " numbers",
           kExitUsage);
  }
  const kinematics::Vec3 place(edit.point[0], edit.point[1], edit.point[2]);
  check_in_reach(k, place, m);
  if (!not_movable.empty()) {
    refuse("the walls are not proven passive wherever they move (" + not_movable +
               "); scene change gates a new place instead",
           kExitGateRefused);
  }
  if (phase == Phase::kStarting || phase == Phase::kEnded) {
    refuse(std::string("the run is ") + name(phase) + "; no walls to move", 1);
  }
  const std::uint64_t offer = moves_.offer(edit.index, place);
  std::optional<loop::WallMoves::Taken> taken;
  if (phase == Phase::kRunning) taken = moves_.await(offer, kSwapTimeout);
  {
    std::lock_guard lock(mutex_);
    cfg_.walls[edit.index].point = place;  // what status, the next edit and the log's next
    cfg_.effective_yaml =                  // configuration say
        config::with_setting(
            cfg_.effective_yaml,
            {"walls[" + std::to_string(edit.index) + "].point", point_yaml(place, m), {}});
  }
  return {{"scene",
           {{"op", "move"},
            {"index", edit.index},
            {"applied_at_tick", taken ? json(taken->tick) : json(nullptr)},
            {"applied_at_ns", taken ? json(taken->time_ns) : json(nullptr)}}}};
}

json RunSession::apply(const std::string& text, const std::string& source,
                       const std::vector<std::string>& sets, const std::string& what,
                       const std::vector<int>* continues, std::uint64_t owner) {
  config::Config running;
  Phase phase = Phase::kStarting;
  {
    std::lock_guard lock(mutex_);
    running = cfg_;
    phase = phase_;
  }
  Prepared next;
  try {
    if (phase == Phase::kStarting || phase == Phase::kEnded) {
      throw ControlRefusal(std::string("the run is ") + name(phase) + "; nothing to reload into");
    }
    next = prepare(running, text, source, sets, continues);
  } catch (const std::exception& e) {  // ControlRefusal, or whatever checking it threw
    swap_.note_refused();              // the RT thread marks it in the tick log
    spdlog::warn("{} from {} refused: {}", what, source, e.what());
    const auto* refusal = dynamic_cast<const ControlRefusal*>(&e);
    throw ControlRefusal(what + " refused: " + e.what(), refusal != nullptr ? refusal->code() : 1);
  }
  return commit(next, phase, source, what, continues, owner);
}

// Swaps `next` in (the loop running) or keeps it for the next arming (a held fault), and makes
// it what the daemon says it runs. Wall i's owner is the owner of the running wall it goes on
// from (continues; none: the configuration's), a new wall's `owner`.
json RunSession::commit(Prepared& next, Phase phase, const std::string& source,
                        const std::string& what, const std::vector<int>* continues,
                        std::uint64_t owner) {
  std::optional<std::uint64_t> first_tick;
  if (phase == Phase::kRunning) first_tick = swap_in(next, source);
  const double k = next.cfg.wall.stiffness, b = next.cfg.wall.damping;
  const std::size_t walls = next.cfg.walls.size();
  const bool scene = scene_.walls != nullptr;
  json out = {{"accepted", true},
              {"applied_at_tick", first_tick ? json(*first_tick) : json(nullptr)},
              {"gate", gate::gate_to_json(next.report)}};
  derated_to_json(next.derated, out);
  {
    std::lock_guard lock(mutex_);
    std::vector<std::uint64_t> owners(next.cfg.walls.size(), 0);
    for (std::size_t i = 0; continues != nullptr && i < owners.size(); ++i) {
      const int from = i < continues->size() ? (*continues)[i] : -1;
      owners[i] = from < 0 ? owner
                  : static_cast<std::size_t>(from) < owners_.size()
                      ? owners_[static_cast<std::size_t>(from)]
                      : 0;
    }
    owners_ = std::move(owners);
    cfg_ = std::move(next.cfg);
    ++reloads_;
    gate_ = out["gate"];
    report_ = next.report;
    summary_.gate = gate_;
    if (next.walls) pending_walls_ = std::move(next.walls);  // not swapped: for the next arming
    if (!next.derated.empty()) {                             // the last derating stays said
      summary_.derated = next.derated;
      derated_ = next.derated;
    }
  }
  const std::string when =
      first_tick ? "from tick " + std::to_string(*first_tick) : "for the next arming";
  if (scene) {
    spdlog::info("{} from {} accepted: {} walls {}", what, source, walls, when);
  } else {
    spdlog::info("{} from {} accepted: wall K {} N/m B {} N s/m {}", what, source, k, b, when);
  }
  return out;
}

// Everything a reload needs before the swap, off the RT thread. Throws ControlRefusal with
// every reason when it may not be applied.
RunSession::Prepared RunSession::prepare(const config::Config& running, const std::string& text,
                                         const std::string& source,
                                         const std::vector<std::string>& sets,
                                         const std::vector<int>* continues) const {
  Prepared p;
  const std::string base = std::filesystem::path(source).parent_path().string();
  try {
    p.cfg = load_config_text_checked(text, source, base.empty() ? "." : base, sets);
  } catch (const config::ConfigError& e) {
    throw ControlRefusal(joined(e.messages()), kExitUsage);
  }
  if (const auto blockers = reload_blockers(running, p.cfg); !blockers.empty()) {
    throw ControlRefusal(joined(blockers), kExitUsage);
  }
  const int delay = session_->device().info().transport_delay_samples;
  p.report = gate::evaluate_gate(p.cfg, delay);
  const gate::GateReport configured = p.report;
  p.derated = derate_stiffness(p.cfg, delay, p.report);
  for (const Derating& d : p.derated) {
    spdlog::warn(
        "reload from {}: DERATED (safety.gate: derate): {} {} N/m fails the gate ({}), swapping "
        "in {} N/m, the largest that passes",
        source, d.key, gate::format_number(d.configured), joined(configured.reasons),
        gate::format_number(d.ran));
  }
  if (!gate_allows(p.report, p.cfg)) {
    throw ControlRefusal("the gate refuses it: " + joined(p.report.reasons), kExitGateRefused);
  }
  if (!p.report.pass) {
    spdlog::error(
        "reload from {}: the gate FAILED but safety.gate is 'warn': swapping in a loop that is "
        "not proven passive ({})",
        source, joined(p.report.reasons));
  }
  p.law = std::make_unique<control::Controller>(control::make_control_law(p.cfg));
  if (scene_.walls) {  // several joints: the walls, each going on from the one it replaces
    p.walls =
        make_scene_walls(p.cfg, session_->device().info(), p.report, scene_.walls.get(), continues);
  }
  return p;
}

// Offers the new law to the RT thread and waits for the tick boundary it is taken at (none
// when the loop ended first). The law it replaced is destroyed here, off the RT thread. An
// offer the running loop does not take in kSwapTimeout is withdrawn and the reload refused:
// the answer, the status and the tick log never name a wall the loop is not rendering.
std::optional<std::uint64_t> RunSession::swap_in(Prepared& next, const std::string& source) {
  if (log_.writer) log_.writer->queue_config_change(next.cfg.effective_yaml);
  const std::optional<std::uint64_t> tick = next.walls
                                                ? offer(scene_swap_, next.walls.get(), source)
                                                : offer(swap_, next.law.get(), source);
  if (!tick) return std::nullopt;
  std::lock_guard lock(mutex_);
  if (next.walls) {
    scene_.walls = std::move(next.walls);  // the replaced walls go here, off the RT thread
  } else {
    active_ = std::move(next.law);  // the replaced law goes here, off the RT thread
  }
  return tick;
}

template <class T>
std::optional<std::uint64_t> RunSession::offer(loop::TickSwap<T>& swap, T* next,
                                               const std::string& source) {
  const std::uint64_t before = swap.swaps();
  if (!swap.offer(next)) {  // reload_mutex_ serialises offers: not expected
    if (log_.writer) log_.writer->withdraw_config_change();
    throw ControlRefusal("reload refused: a previous reload is still being applied");
  }
  const loop::SwapOutcome outcome = loop::await_swap(swap, next, before, kSwapTimeout);
  if (outcome != loop::SwapOutcome::kTaken) {
    if (log_.writer) log_.writer->withdraw_config_change();
    if (outcome == loop::SwapOutcome::kLoopEnded) return std::nullopt;
    swap.note_refused();
    const std::string why = "the servo loop reached no tick boundary in " +
                            std::to_string(kSwapTimeout.count() / 1000) +
                            " s (starved of the CPU?); nothing changed";
    spdlog::warn("reload from {} refused: {}", source, why);
    throw ControlRefusal("reload refused: " + why);
  }
  swap.retire();  // the caller owns what it replaced and lets it go
  return swap.last_swap_tick();
}

// SIGHUP: the file the run was started with, read again, with the same --set arguments.
json RunSession::reload_file() {
  if (options_.config.path.empty()) {
    spdlog::warn(
        "SIGHUP: running the embedded default configuration: nothing to reload "
        "(start with --config FILE)");
    return nullptr;
  }
  std::string text;
  try {
    text = read_config_file(options_.config.path);
  } catch (const config::ConfigError& e) {
    spdlog::warn("SIGHUP: reload refused: {}", e.what());
    swap_.note_refused();
    return nullptr;
  }
  try {
    return reload(text, options_.config.path, options_.config.sets);
  } catch (const std::exception&) {
    return nullptr;  // refused: already logged and marked in the tick log
  }
}

}  // namespace hapticd::service
