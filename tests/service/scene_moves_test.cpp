// A client's wall moves (docs/operations.md, scene requests: move): with no new gate when the
// gate proved the walls movable, taken at the next tick boundary, marked in the tick log and
// replayed bit for bit; the simulated delta resting on a moved floor follows it; what is
// refused (walls not movable, a wrong index, point or reach) never reaches a tick.
#include <gtest/gtest.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "daemon.h"
#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

// config/sim-delta-scene.yaml: the hand holds the delta 20 mm below its start (z = 0.09 m)
// with k_h = 200 N/m on a floor of K = 500 N/m. At rest the two springs balance:
// 200 (z - 0.09) = 500 (floor - z).
double rest_z(double floor) { return (500.0 * floor + 200.0 * 0.09) / 700.0; }

// Where the effector rests along z once it has been in contact a further `ticks` ticks.
double rested_z(const Daemon& d, int ticks) {
  const int from = d.status()["counters"]["loop"]["contact_ticks"].get<int>();
  const json s = d.wait_status([&](const json& j) {
    return j["counters"]["loop"]["contact_ticks"].get<int>() > from + ticks;
  });
  return s["task_position"][2].get<double>();
}

json answer(const ProcessResult& r) {
  const json j = json::parse(r.out, nullptr, false);
  EXPECT_FALSE(j.is_discarded()) << r.out << r.err;
  return j;
}

std::vector<telemetry::TickRecord> moves_in(const std::string& log) {
  std::vector<telemetry::TickRecord> out;
  for (const telemetry::TickRecord& r : telemetry::read_log(log).records) {
    if (r.marker == telemetry::kMarkerWallMoved) out.push_back(r);
  }
  return out;
}

TEST(SceneMoves, AMovedFloorIsFeltFromTheTickThatTookItAndTheLogReplaysIt) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
  ASSERT_TRUE(d.ready());
  EXPECT_NEAR(rested_z(d, 700), rest_z(0.105), 3e-4);

  const ProcessResult moved = d.ctl({"--json", "scene", "move", "0", "0", "0", "0.095"});
  ASSERT_EQ(moved.exit_code, 0) << moved.out << moved.err;
  const json m = answer(moved)["scene"];
  EXPECT_EQ(m["op"], "move");
  ASSERT_TRUE(m["applied_at_tick"].is_number()) << m.dump();
  EXPECT_GT(m["applied_at_ns"].get<std::int64_t>(), 0);
  // 10 mm at 0.25 m/s is 40 ms of sliding; the hand follows within a second.
  EXPECT_NEAR(rested_z(d, 1500), rest_z(0.095), 3e-4);

  // A change gated afterwards keeps the moved point: the document carries it.
  ASSERT_EQ(d.ctl({"scene", "change", "0", R"({"damping": 0.1})"}).exit_code, 0);
  EXPECT_NEAR(rested_z(d, 1000), rest_z(0.095), 3e-4);

  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  const std::vector<telemetry::TickRecord> marks = moves_in(d.log());
  ASSERT_EQ(marks.size(), 1u);
  EXPECT_EQ(marks[0].tick, m["applied_at_tick"].get<std::uint64_t>());
  EXPECT_EQ(marks[0].deepest_wall, 0);
  EXPECT_EQ(marks[0].task_position[2], 0.095);
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(json::parse(replay.out)["reproduced"]["identical"], true) << replay.out;
}

TEST(SceneMoves, WhatIsRefusedSaysWhyAndNeverReachesATick) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
  ASSERT_TRUE(d.ready());
  const auto refused = [&](const std::vector<std::string>& args, int code, const std::string& why) {
    std::vector<std::string> all = {"scene", "move"};
    all.insert(all.end(), args.begin(), args.end());
    const ProcessResult r = d.ctl(all);
    EXPECT_EQ(r.exit_code, code) << r.out << r.err;
    EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
  };
  refused({"1", "0", "0", "0.1"}, 2, "\"index\": 1 names no wall (1 walls)");
  refused({"0", "0", "0.1"}, 2, "the device has 3 task axes, the point 2 numbers");
  refused({"0", "0", "0", "0.5"}, 2, "\"point\"[2]: 0.5 m is out of reach");

  RawClient raw(d.socket());
  ASSERT_TRUE(raw.send(R"({"v":1,"cmd":"scene","op":"move","index":0,"point":[0,0,"NaN"]})"
                       "\n"));
  // JSON has no NaN or infinity (1e999 is no JSON number): a string is the way to send one.
  const json nan = json::parse(raw.line(), nullptr, false);
  EXPECT_EQ(nan["code"], 2) << nan.dump();
  EXPECT_NE(nan["error"].get<std::string>().find(
                "\"point\"[2]: must be a finite number (m), got \"NaN\""),
            std::string::npos)
      << nan.dump();

  // A gated change that makes the floor too stiff to be moved anywhere: it still passes where
  // it is, but moves are refused from then on with the gate's numbers.
  const ProcessResult stiff = d.ctl({"scene", "change", "0", R"({"stiffness": 3500})"});
  ASSERT_EQ(stiff.exit_code, 0) << stiff.err;
  refused({"0", "0", "0", "0.1"}, 3, "not proven passive wherever they move (walls[0]: b_req");

  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  EXPECT_TRUE(moves_in(d.log()).empty());
}

// The box of config/sim-delta.yaml passes where it is, but its opposite faces moved onto each
// other would not: moves are refused, saying where.
TEST(SceneMoves, ABoxWhoseFacesCouldMeetIsNotMovable) {
  const ProcessResult check = run_process(
      {hapticd_binary(), "check", "--config", source_dir() + "/config/sim-delta.yaml", "--json"});
  ASSERT_EQ(check.exit_code, 0) << check.err;
  const json w = json::parse(check.out)["workspace"];
  EXPECT_EQ(w["pass"], true);
  EXPECT_EQ(w["movable"], false);
  EXPECT_NE(w["not_movable"].get<std::string>().find("every wall acting at once"),
            std::string::npos)
      << w.dump();
}

}  // namespace
}  // namespace hapticd::testing
