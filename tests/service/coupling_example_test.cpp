// Naghshtabrizi & Hespanha's Example 1 (T = 0.02, b = 10, K = 1000, B = 20): the gate refuses the
// bare wall and passes it behind the paper's C(z); in a run with a hand pressing in, the coupled
// wall settles while the bare wall (forced on with safety.gate: warn) keeps bouncing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

double max_speed_in_last(const std::vector<telemetry::TickRecord>& r, std::size_t n) {
  double v = 0.0;
  for (std::size_t k = r.size() - n; k < r.size(); ++k) v = std::max(v, std::abs(r[k].velocity));
  return v;
}

TEST(CouplingExample1, GateRefusesTheBareWallAndPassesTheCoupledOne) {
  const ProcessResult bare = run_process({hapticd_binary(), "check", "--json", "--config",
                                          coupling_example(), "--set", "wall.coupling="});
  EXPECT_EQ(bare.exit_code, 3);
  const nlohmann::json b = nlohmann::json::parse(bare.out);
  EXPECT_NEAR(b["passivity"]["required_damping"].get<double>(), 30.0, 1e-9);
  EXPECT_EQ(b["verdict"], "fail");

  const ProcessResult coupled =
      run_process({hapticd_binary(), "check", "--json", "--config", coupling_example()});
  EXPECT_EQ(coupled.exit_code, 0);
  const nlohmann::json c = nlohmann::json::parse(coupled.out);
  EXPECT_EQ(c["verdict"], "pass");
  EXPECT_TRUE(c["coupling"]["dspr"].get<bool>());
  EXPECT_EQ(c["coupling"]["static_stiffness"].get<double>(), 0.0);  // yields under a steady push
  EXPECT_LT(c["passivity"]["required_damping"].get<double>(), 1.0);
}

TEST(CouplingExample1, CoupledWallSettlesBareWallKeepsBouncing) {
  const std::string coupled_log = temp_path("ex1_coupled.hlog"),
                    bare_log = temp_path("ex1_bare.hlog");
  const std::string bare_sum = temp_path("ex1_bare.json");
  ASSERT_EQ(run_process({hapticd_binary(), "run", "--config", coupling_example(), "--duration",
                         "20", "--log", coupled_log})
                .exit_code,
            0);
  const ProcessResult bare =
      run_process({hapticd_binary(), "run", "--config", coupling_example(), "--duration", "20",
                   "--log", bare_log, "--summary-json", bare_sum, "--set",
                   "wall.coupling=", "--set", "safety.gate=warn"});
  ASSERT_EQ(bare.exit_code, 0) << bare.err;
  const auto coupled = telemetry::read_log(coupled_log).records;
  const auto bouncing = telemetry::read_log(bare_log).records;
  ASSERT_EQ(coupled.size(), 1000u);
  // Last 5 s: the coupled wall is at rest (below one encoder count per sample, 0.5 mm/s)...
  EXPECT_LT(max_speed_in_last(coupled, 250), 1e-4);
  // ...the bare wall is still bouncing in and out of contact at a sizeable speed,
  EXPECT_GT(max_speed_in_last(bouncing, 250), 0.3);
  // and the sim measures the device handing energy to the passive hand: not passive.
  EXPECT_LT(nlohmann::json::parse(read_file(bare_sum))["operator_work_j"].get<double>(), -1.0);
}

}  // namespace
}  // namespace hapticd::testing
