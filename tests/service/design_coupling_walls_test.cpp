// `hapticd design-coupling` end to end, as a user runs it: on Naghshtabrizi and Hespanha's
// Example 1 against the paper's printed C(z), and on walls the gate refuses, where every
// design printed must pass `check` and `verify` and settle in `run`. Each design calls the SDP
// solver, so these have their own ctest label, `design` (main stage only, tools/quickstart.sh);
// the 20-wall sweep is also labelled `slow`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "design_coupling_support.h"
#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

std::vector<std::string> example_with(const std::vector<std::string>& extra) {
  return concat({"--config", coupling_example()}, extra);
}

double felt(const json& d) {
  return d.contains("designed") ? d["designed"]["gamma_felt"].get<double>()
                                : std::numeric_limits<double>::infinity();
}

// Order 3 (the paper's) against the paper's printed C(z), by both measures, and through the
// gate and `verify`. Then what the order buys on the felt measure: order 3 against the family
// d z/(z-1) + D_c alone (order 1: measured 7.100 against 5.369), and order 4 against order 3
// (measured 5.229, 2.6 % better; order 5 5.218): order 4 is reached from order 3's design by a
// pole added at z = 0, which keeps order 3's coupling in reach, then placed and moved, and
// must beat it by 1 %. The paper's own measure cannot show any of this: every admissible
// coupling sits on its floor |W(1) E(1)|^2 (docs/math.md). One test, so that order 3 is
// designed once (ctest runs each test in a process of its own).
TEST(DesignCoupling, Example1BeatsThePapersCouplingAndOrder4ImprovesOnOrder3) {
  const json d3 = design_coupling_json(example_with({"--order", "3"}));
  ASSERT_EQ(d3["exit_code"], 0) << d3.dump(1);
  EXPECT_EQ(d3["status"], "designed");
  EXPECT_TRUE(d3["gate"]["pass"].get<bool>());
  EXPECT_TRUE(d3["gate"]["dspr"].get<bool>());
  // The paper's printed C(z) (the configured coupling): hapticd's measure is the DC floor
  // (0.13 x 1000)^2, not the paper's 23.45; the felt one is 27.8.
  const json& paper = d3["configured_coupling"];
  EXPECT_NEAR(paper["gamma_configured"].get<double>(), 16900.0, 0.1);
  EXPECT_NEAR(paper["gamma_felt"].get<double>(), 27.82, 0.01);
  const json& des = d3["designed"];
  EXPECT_NEAR(des["gamma_configured"].get<double>(), 16900.0, 16900.0 * 1e-6);  // the floor
  // Measured 5.369, a fifth of the paper's; the cone complementarity stage alone 6.636. A
  // dense scan of the stable order-3 pole pairs found none below 5.36 (docs/math.md).
  EXPECT_LT(felt(d3), 5.45);
  EXPECT_LT(felt(d3), 0.9 * d3["gamma_seed"].get<double>());
  EXPECT_EQ(des["static_stiffness"].get<double>(), 0.0);  // Theorem 1's pole at z = 1
  // The gate itself, with the YAML pasted in, and the measured passivity threshold.
  const std::vector<std::string> pasted = example_with(pasted_coupling(d3));
  EXPECT_EQ(run_process(concat({hapticd_binary(), "check"}, pasted)).exit_code, 0);
  const ProcessResult v = run_process(concat({hapticd_binary(), "verify", "--json"}, pasted));
  ASSERT_EQ(v.exit_code, 0) << v.out << v.err;
  EXPECT_EQ(json::parse(v.out)["verdict"], "agree");

  const json d1 = design_coupling_json(example_with({"--order", "1"}));
  const json d4 = design_coupling_json(example_with({"--order", "4"}));
  for (const json* d : {&d1, &d4}) {
    ASSERT_EQ((*d)["exit_code"], 0) << d->dump(1);
    EXPECT_TRUE((*d)["gate"]["pass"].get<bool>());
    // On the floor: no admissible coupling goes below it, and these barely rise above it.
    EXPECT_NEAR((*d)["designed"]["gamma_configured"].get<double>(), 16900.0, 16900.0 * 1e-6);
  }
  const double g1 = felt(d1), g3 = felt(d3), g4 = felt(d4);
  EXPECT_GT(g1, 1.2 * g3) << g1 << " against " << g3;
  EXPECT_LT(g4, 0.99 * g3) << g4 << " against " << g3;
}

// Over the last n ticks: the largest distance the device moved back against its net direction
// (for no net motion, the smaller of the two directions). A device at rest, or creeping one
// way (a coupled wall yields under a steady push, H(1) = 0, slowing as the hand's spring
// relaxes), goes back by at most the encoder's one-count dither; a bouncing wall by its bounce.
double retrace_in_last(const std::vector<telemetry::TickRecord>& r, std::size_t n) {
  const std::size_t first = r.size() - std::min(n, r.size());
  const auto against = [&](double sign) {
    double furthest = -std::numeric_limits<double>::infinity(), worst = 0.0;
    for (std::size_t k = first; k < r.size(); ++k) {
      furthest = std::max(furthest, sign * r[k].position);
      worst = std::max(worst, furthest - sign * r[k].position);
    }
    return worst;
  };
  const double net = r.back().position - r[first].position;
  if (net == 0.0) return std::min(against(1.0), against(-1.0));
  return against(net > 0.0 ? 1.0 : -1.0);
}

// `sets` make a wall the gate refuses bare. The design is run with a short search (16 steps of
// at most 4 SDPs); a design it prints must pass `check` and `verify` (the measured passivity
// threshold agrees) and settle in a 20 s sim run with the example's firm hand pressing. False
// when nothing was designed (exit 1), which must then print no coupling.
bool designs_a_safe_coupling(const std::vector<std::string>& sets, const std::string& name) {
  const std::vector<std::string> cfg = example_with(sets);
  EXPECT_EQ(run_process(concat({hapticd_binary(), "check"}, cfg)).exit_code, 3) << "not refused";
  const json d = design_coupling_json(concat(cfg, {"--max-steps", "16", "--max-iterations", "4"}));
  SCOPED_TRACE(name + ": " + d.dump());
  if (d["exit_code"] != 0) {
    EXPECT_EQ(d.count("coupling"), 0u);  // never printed as a coupling
    return false;
  }
  const std::vector<std::string> withc = concat(cfg, pasted_coupling(d));
  EXPECT_EQ(run_process(concat({hapticd_binary(), "check"}, withc)).exit_code, 0);
  const ProcessResult v = run_process(concat({hapticd_binary(), "verify", "--json"}, withc));
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  const std::string log = temp_path("design_" + name + ".hlog");
  const ProcessResult run =
      run_process(concat({hapticd_binary(), "run", "--duration", "20", "--log", log}, withc));
  EXPECT_EQ(run.exit_code, 0) << run.err;
  const auto records = telemetry::read_log(log).records;
  EXPECT_FALSE(records.empty());
  // No oscillation over the last quarter: back by at most 2 encoder counts (1e-5 m each),
  // counted whole (a difference of two positions in metres is 2 counts give or take a bit).
  if (!records.empty()) {
    EXPECT_LE(std::round(retrace_in_last(records, records.size() / 4) / 1e-5), 2.0);
  }
  return true;
}

std::vector<std::string> wall(int rate_hz, double b, double k, double damping, int delay) {
  return {"--set", "loop.rate_hz=" + std::to_string(rate_hz),
          "--set", "device.damping=" + std::to_string(b),
          "--set", "wall.stiffness=" + std::to_string(k),
          "--set", "wall.damping=" + std::to_string(damping),
          "--set", "wall.delay_samples=" + std::to_string(delay),
          "--set", "wall.coupling="};
}

// Three refused walls from the sweep below, one per delay the gate sees, chosen to span it: a
// stiff wall at 50 Hz (the paper's situation), one sample of delay at 200 Hz with a light
// device, two samples at 500 Hz, whose coupled wall creeps the longest (the settle measure's
// hardest case). About 12 s of CPU.
TEST(DesignCoupling, ThreeRefusedWallsEveryPrintedDesignPassesVerifiesAndSettles) {
  EXPECT_TRUE(designs_a_safe_coupling(wall(50, 3.5, 2680, 0.5, 0), "50hz_delay0"));
  EXPECT_TRUE(designs_a_safe_coupling(wall(200, 2.7, 2885, 0.37, 1), "200hz_delay1"));
  EXPECT_TRUE(designs_a_safe_coupling(wall(500, 4.06, 1651, 2.54, 2), "500hz_delay2"));
}

// The 20 random refused walls (K, B, T, b, delay 0-2), the same 20 every run: drawn in
// order from one seed, each draw kept once the gate refuses it bare.
std::vector<std::vector<std::string>> refused_walls() {
  std::mt19937 rng(2025);
  const auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  std::vector<std::vector<std::string>> walls;
  while (walls.size() < 20) {
    const int rate = std::vector<int>{50, 100, 200, 500, 1000}[rng() % 5];
    const double b = uniform(1.0, 10.0), k = uniform(300.0, 3000.0), damping = uniform(0.0, 3.0);
    std::vector<std::string> sets = wall(rate, b, k, damping, static_cast<int>(rng() % 3));
    if (run_process(concat({hapticd_binary(), "check"}, example_with(sets))).exit_code == 3) {
      walls.push_back(std::move(sets));
    }
  }
  return walls;
}

// Half of them: about 75 s of CPU, labelled `slow` (tests/service/CMakeLists.txt), each half
// its own test so that two cores share the sweep. All 20 were designed on CSDP 6.2
// (2026-11-27), the pole search 12 to 52 % below the cone complementarity stage's gamma on
// each; the search must find at least 8 of each 10 (the rest are refused with exit 1).
void design_half_of_the_sweep(std::size_t first) {
  const auto walls = refused_walls();
  int designed = 0;
  for (std::size_t n = first; n < first + 10; ++n) {
    if (designs_a_safe_coupling(walls[n], "random_wall_" + std::to_string(n))) ++designed;
  }
  EXPECT_GE(designed, 8);
}

TEST(DesignCouplingSweep, RandomRefusedWalls0To9EveryPrintedDesignPassesVerifiesAndSettles) {
  design_half_of_the_sweep(0);
}

TEST(DesignCouplingSweep, RandomRefusedWalls10To19EveryPrintedDesignPassesVerifiesAndSettles) {
  design_half_of_the_sweep(10);
}

}  // namespace
}  // namespace hapticd::testing
