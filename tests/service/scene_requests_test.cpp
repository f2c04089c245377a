// The walls of a device of several joints changed while it runs (docs/operations.md, live
// reload and scene requests): a reload of the whole file and a client's scene request (add,
// change, remove one wall) are checked, gated and swapped in at a tick boundary, each wall
// going on from the one it replaces; the simulated delta pressed into its corner rests against
// the moved face; what is refused (the gate, a wrong request, a new mechanism, a device of one
// joint) changes nothing; the log replays bit for bit across every swap.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "daemon.h"
#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

// config/sim-delta.yaml held pressed into its corner (a hold as long as the run) in real time,
// with each replacement of `edits` (text, new text) made.
std::string held_delta(const std::vector<std::pair<std::string, std::string>>& edits) {
  std::string yaml = read_file(source_dir() + "/config/sim-delta.yaml");
  // Real time, and the Daemon's overrun streak (a reload must not change either).
  std::vector<std::pair<std::string, std::string>> all = {
      {"hold: 1.5", "hold: 200"},
      {"clock: freerun", "clock: realtime\n  overrun_fault_streak: 1000000000"}};
  all.insert(all.end(), edits.begin(), edits.end());
  for (const auto& [from, to] : all) {
    const auto at = yaml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) yaml.replace(at, from.size(), to);
  }
  return yaml;
}

// Once the delta has pressed into its corner a while: where the effector is along x.
double pressed_x(const Daemon& d) {
  const json s = d.wait_status(
      [](const json& j) { return j["counters"]["loop"]["contact_ticks"].get<int>() > 1500; });
  return s["task_position"][0].get<double>();
}

// Stops `d` and replays its log, which must reproduce every tick bit for bit: the replay's
// answer.
json stop_and_replay(Daemon& d) {
  EXPECT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
  const json r = json::parse(replay.out, nullptr, false);
  EXPECT_EQ(r["reproduced"]["identical"], true) << r.dump(2);
  return r;
}

// A device of several joints reloads its walls at a tick boundary: the +x face moved 10 mm
// out, the effector pressed into the corner follows it (it rests against the moved face),
// each wall going on from the one it replaces; a reload the gate refuses (a face too stiff)
// and one that changes the mechanism change nothing; the log replays bit for bit across the
// swap.
TEST(SceneReload, ADeltaReloadsItsWallsAtATickBoundaryAndRestsAgainstTheMovedFace) {
  const std::string start = write_temp("delta-held.yaml", held_delta({}));
  Daemon d({"--config", start, "--duration", "120"});
  ASSERT_TRUE(d.ready());
  const double x0 = pressed_x(d);
  EXPECT_GT(x0, 0.02) << "pressed beyond the +x face";

  const ProcessResult moved =
      d.ctl({"--json", "reload",
             write_temp("delta-moved.yaml",
                        held_delta({{"point: [0.02, 0, 0.11]", "point: [0.03, 0, 0.11]"}}))});
  ASSERT_EQ(moved.exit_code, 0) << moved.out << moved.err;
  const json accepted = json::parse(moved.out)["reload"];
  EXPECT_EQ(accepted["accepted"], true);
  ASSERT_TRUE(accepted["applied_at_tick"].is_number()) << accepted.dump();
  const auto boundary = accepted["applied_at_tick"].get<std::uint64_t>();
  const json after = d.wait_status(
      [&](const json& j) { return j["tick"].get<std::uint64_t>() > boundary + 1500; });
  // The hand's spring (200 N/m) and the face (500 N/m) share the move: 10 mm K / (K + k_h).
  EXPECT_NEAR(after["task_position"][0].get<double>(), x0 + 0.01 * 500.0 / 700.0, 0.0005)
      << "at rest against the face 10 mm further out";
  EXPECT_EQ(after["reloads"], 1);

  const ProcessResult stiff =
      d.ctl({"reload",
             write_temp("delta-stiff.yaml", held_delta({{"stiffness: 500, damping: 0.05}",
                                                         "stiffness: 500000, damping: 0.05}"}}))});
  EXPECT_EQ(stiff.exit_code, 3) << stiff.out << stiff.err;
  const ProcessResult mechanism =
      d.ctl({"reload", write_temp("delta-kind.yaml",
                                  held_delta({{"kind: delta", "kind: delta\n    thigh: 0.07"}}))});
  EXPECT_EQ(mechanism.exit_code, 2) << mechanism.out << mechanism.err;
  EXPECT_TRUE(has(mechanism.out + mechanism.err, "device.kinematics: a different mechanism"))
      << mechanism.out << mechanism.err;
  EXPECT_EQ(d.status()["reloads"], 1) << "the refused reloads changed nothing";

  const json r = stop_and_replay(d);
  EXPECT_EQ(r["reloads"], 1);
}

// hapticctl scene ARGS --json against `d`: the exit code and the answer.
std::pair<int, json> scene(const Daemon& d, const std::vector<std::string>& args) {
  std::vector<std::string> all = {"--json", "scene"};
  all.insert(all.end(), args.begin(), args.end());
  const ProcessResult r = d.ctl(all);
  return {r.exit_code, json::parse(r.out, nullptr, false)};
}

// A client changes one wall at a time: each accepted change governs from the tick it names
// and the effector follows the moved face; each refused one (the gate, an index that names no
// wall, a key out of range, a malformed request) is answered with the reason and changes
// nothing; the log replays bit for bit across every swap.
TEST(SceneRequests, AddChangeAndRemoveOneWallAtATimeOrRefuseWithTheReason) {
  const std::string start = write_temp("delta-scene.yaml", held_delta({}));
  Daemon d({"--config", start, "--duration", "120"});
  ASSERT_TRUE(d.ready());
  const double x0 = pressed_x(d);

  // Change: the +x face 10 mm out; the effector rests against it.
  auto [code, answer] = scene(d, {"change", "0", R"({"point": [0.03, 0, 0.11]})"});
  ASSERT_EQ(code, 0) << answer.dump();
  EXPECT_EQ(answer["scene"]["op"], "change");
  EXPECT_EQ(answer["scene"]["walls"], 6);
  ASSERT_TRUE(answer["scene"]["applied_at_tick"].is_number()) << answer.dump();
  const auto moved_at = answer["scene"]["applied_at_tick"].get<std::uint64_t>();
  json s = d.wait_status(
      [&](const json& j) { return j["tick"].get<std::uint64_t>() > moved_at + 1500; });
  EXPECT_NEAR(s["task_position"][0].get<double>(), x0 + 0.01 * 500.0 / 700.0, 0.0005);
  EXPECT_EQ(s["walls"][0]["stiffness"], 500.0);

  // Add: a seventh wall out of reach; then remove it again.
  std::tie(code, answer) =
      scene(d, {"add", R"({"point": [0, 0, 0.16], "normal": [0, 0, 1], "stiffness": 400})"});
  ASSERT_EQ(code, 0) << answer.dump();
  EXPECT_EQ(answer["scene"]["index"], 6);
  EXPECT_EQ(answer["scene"]["walls"], 7);
  EXPECT_EQ(d.status()["walls"].size(), 7u);
  EXPECT_EQ(d.status()["walls"][6]["stiffness"], 400.0);

  // Refused, each with its reason, nothing changed: too stiff for the gate, a wall that is not
  // there, a stiffness below zero.
  std::tie(code, answer) = scene(d, {"change", "1", R"({"stiffness": 500000})"});
  EXPECT_EQ(code, 3) << answer.dump();
  EXPECT_NE(answer["error"].get<std::string>().find("scene change refused: the gate refuses it"),
            std::string::npos)
      << answer.dump();
  std::tie(code, answer) = scene(d, {"remove", "9"});
  EXPECT_EQ(code, 2) << answer.dump();
  EXPECT_NE(answer["error"].get<std::string>().find("\"index\": 9 names no wall (7 walls: 0..6)"),
            std::string::npos)
      << answer.dump();
  std::tie(code, answer) = scene(d, {"change", "2", R"({"stiffness": -5})"});
  EXPECT_EQ(code, 2) << answer.dump();
  EXPECT_NE(answer["error"].get<std::string>().find("walls[2].stiffness"), std::string::npos)
      << answer.dump();
  RawClient raw(d.socket());
  ASSERT_TRUE(raw.send(R"({"v": 1, "cmd": "scene", "op": "rotate", "index": 0})"
                       "\n"));
  const json malformed = json::parse(raw.line());
  EXPECT_EQ(malformed["ok"], false);
  EXPECT_NE(
      malformed["error"].get<std::string>().find("\"op\" must be one of add, change, remove, move"),
      std::string::npos)
      << malformed.dump();
  ASSERT_TRUE(raw.send(R"({"v": 1, "cmd": "scene", "op": "remove", "index": -1})"
                       "\n"));
  const std::string negative = raw.line();
  EXPECT_NE(negative.find(R"(remove needs \"index\")"), std::string::npos) << negative;
  s = d.status();
  EXPECT_EQ(s["walls"].size(), 7u) << "the refusals changed nothing";
  EXPECT_EQ(s["walls"][1]["stiffness"], 500.0);
  EXPECT_EQ(s["walls"][2]["stiffness"], 500.0);

  std::tie(code, answer) = scene(d, {"remove", "6"});
  ASSERT_EQ(code, 0) << answer.dump();
  EXPECT_EQ(d.status()["walls"].size(), 6u);
  EXPECT_EQ(d.status()["reloads"], 3);

  const json r = stop_and_replay(d);
  EXPECT_EQ(r["reloads"], 3);
}

// A device of one joint has one wall, which a reload changes: a scene request says so.
TEST(SceneRequests, ADeviceOfOneJointRefusesThemNamingTheReload) {
  Daemon d({"--duration", "60", "--set", "loop.clock=realtime"});
  ASSERT_TRUE(d.ready());
  const auto [code, answer] = scene(d, {"add", R"({"point": [0.1], "normal": [1]})"});
  EXPECT_EQ(code, 2) << answer.dump();
  EXPECT_NE(answer["error"].get<std::string>().find("a device of one joint reloads its wall"),
            std::string::npos)
      << answer.dump();
}

}  // namespace
}  // namespace hapticd::testing
