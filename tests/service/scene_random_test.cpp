// Twenty random scene changes on the running delta (docs/clients.md; walls and attractors):
// each is either admitted,
// and then `hapticd verify` measures the scene it made passive, or refused with the gate's
// numbers; and nothing refused reaches a tick: the log's swaps are the admitted changes alone,
// and no configuration it recorded holds a refused wall. Label slow (a verify per admitted
// change): the main stage runs it.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "daemon.h"
#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

struct Wall {
  double point[3];
  double normal[3];
  double stiffness;
  double damping;
  bool attractor = false;  // a spring-damper to its point: no normal
};

std::string num(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

std::string vec(const double (&v)[3]) {
  return "[" + num(v[0]) + ", " + num(v[1]) + ", " + num(v[2]) + "]";
}

std::string wall_json(const Wall& w) {
  const std::string shape =
      w.attractor ? R"({"kind": "attractor", "point": )" + vec(w.point)
                  : R"({"point": )" + vec(w.point) + R"(, "normal": )" + vec(w.normal);
  return shape + R"(, "stiffness": )" + num(w.stiffness) + R"(, "damping": )" + num(w.damping) +
         "}";
}

// config/sim-delta-scene.yaml with `walls` as given.
std::string scene_yaml(const std::vector<Wall>& walls) {
  std::string yaml = read_file(source_dir() + "/config/sim-delta-scene.yaml");
  const auto at = yaml.find("walls:");
  const auto end = yaml.find("safety:");
  std::string list = "walls:\n";
  for (const Wall& w : walls) list += "  - " + wall_json(w) + "\n";
  return yaml.substr(0, at) + list + yaml.substr(end);
}

struct Random {
  std::mt19937 rng{36};
  double uniform(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(rng); }
  std::size_t below(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  }
  // Within the delta's workspace, away from its edges.
  void point(double (&p)[3]) {
    p[0] = uniform(-0.03, 0.03);
    p[1] = uniform(-0.03, 0.03);
    p[2] = uniform(0.09, 0.13);
  }
  // One in four an attractor, whose stiffness the delta's least damping in any direction
  // bounds near 800 N/m: about half of them pass.
  Wall wall() {
    Wall w{};
    point(w.point);
    w.attractor = below(4) == 0;
    if (!w.attractor) w.normal[below(3)] = below(2) == 0 ? 1.0 : -1.0;
    w.stiffness = w.attractor ? uniform(100.0, 1600.0) : uniform(200.0, 6000.0);
    w.damping = uniform(0.0, 0.2);
    return w;
  }
};

TEST(SceneRandom, EachChangeIsAdmittedAndMeasuredPassiveOrRefusedWithTheNumbers) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "600"});
  ASSERT_TRUE(d.ready());
  RawClient c(d.socket());
  std::vector<Wall> walls = {{{0, 0, 0.105}, {0, 0, -1}, 500, 0.05}};
  Random r;
  std::size_t admitted = 0, refused = 0, swaps = 0, moves = 0;
  std::vector<double> refused_stiffness;
  std::size_t attractors = 0;  // attractors asked for
  for (int k = 0; k < 20; ++k) {
    const std::size_t kind = walls.size() < 2 ? r.below(2) * 3 : r.below(4);
    std::vector<Wall> next = walls;
    std::string request;
    std::string what;
    double stiffness = 0.0;
    if (kind == 0) {  // add
      next.push_back(r.wall());
      stiffness = next.back().stiffness;
      attractors += next.back().attractor ? 1 : 0;
      request =
          R"({"v":1,"cmd":"scene","op":"add","keep":true,"wall":)" + wall_json(next.back()) + "}";
      what = "add " + wall_json(next.back());
    } else if (kind == 1) {  // a new stiffness
      const std::size_t i = r.below(walls.size());
      next[i].stiffness = stiffness = r.uniform(200.0, 6000.0);
      request = R"({"v":1,"cmd":"scene","op":"change","index":)" + std::to_string(i) +
                R"(,"wall":{"stiffness":)" + num(stiffness) + "}}";
      what = "change walls[" + std::to_string(i) + "].stiffness to " + num(stiffness);
    } else if (kind == 2) {
      const std::size_t i = r.below(walls.size());
      next.erase(next.begin() + static_cast<std::ptrdiff_t>(i));
      request = R"({"v":1,"cmd":"scene","op":"remove","index":)" + std::to_string(i) + "}";
      what = "remove walls[" + std::to_string(i) + "]";
    } else {
      const std::size_t i = r.below(walls.size());
      r.point(next[i].point);
      request = R"({"v":1,"cmd":"scene","op":"move","index":)" + std::to_string(i) +
                R"(,"point":)" + vec(next[i].point) + "}";
      what = "move walls[" + std::to_string(i) + "] to " + vec(next[i].point);
    }
    ASSERT_TRUE(c.send(request + "\n"));
    const json a = json::parse(c.line(), nullptr, false);
    SCOPED_TRACE("change " + std::to_string(k) + ": " + what + ": " + a.dump());
    if (a["ok"] == true) {
      ++admitted;
      (kind == 3 ? moves : swaps) += 1;
      walls = next;
      const std::string file =
          write_temp("random-" + std::to_string(k) + ".yaml", scene_yaml(walls));
      const ProcessResult v = run_process({hapticd_binary(), "verify", "--config", file, "--json"});
      EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
      const json j = json::parse(v.out, nullptr, false);
      for (const json& w : j["walls"]) {
        EXPECT_EQ(w["measured_passive"], true) << w.dump();
        EXPECT_EQ(w["verdict"], "agree") << w.dump();
      }
      continue;
    }
    ++refused;
    EXPECT_EQ(a["code"], 3) << "refused for what is not the gate";
    const std::string error = a["error"].get<std::string>();
    EXPECT_TRUE(error.find("b_req") != std::string::npos ||
                error.find("least eigenvalue") != std::string::npos)
        << "a refusal without the gate's numbers: " << error;
    if (stiffness > 0.0) refused_stiffness.push_back(stiffness);
  }
  EXPECT_GT(admitted, 3u);
  EXPECT_GT(refused, 3u);
  EXPECT_GT(attractors, 0u);
  std::printf("admitted %zu, refused %zu, attractors asked %zu\n", admitted, refused, attractors);
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  const telemetry::LogContents log = telemetry::read_log(d.log());
  std::size_t logged_swaps = 0, logged_moves = 0;
  for (const telemetry::TickRecord& rec : log.records) {
    logged_swaps += rec.marker == telemetry::kMarkerReloadAccepted ? 1 : 0;
    logged_moves += rec.marker == telemetry::kMarkerWallMoved ? 1 : 0;
  }
  EXPECT_EQ(logged_swaps, swaps);
  EXPECT_EQ(logged_moves, moves);
  for (const auto& change : log.reloads) {
    for (const double k : refused_stiffness) {  // as the daemon writes it: JSON's digits
      EXPECT_EQ(change.config_text.find(json(k).dump()), std::string::npos)
          << "a refused stiffness " << json(k).dump() << " reached the loop at tick "
          << change.first_tick;
    }
  }
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(json::parse(replay.out)["reproduced"]["identical"], true) << replay.out;
}

}  // namespace
}  // namespace hapticd::testing
