// `hapticd curves`, the JSON tools/hapticd-plot draws: the Z-width with the configured point,
// its measured points agreeing with the analysis, and the Nyquist points with the verdicts.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

TEST(CliCurves, ZwidthMeasuredPointsLieOnTheAnalyticCurve) {
  const ProcessResult r = run_process({hapticd_binary(), "curves"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["configured"]["stiffness"], 2000.0);
  EXPECT_EQ(j["configured"]["pass"], true);
  EXPECT_EQ(j["zwidth"]["points"][0]["max_stiffness"].get<double>(), 3600.0);  // 2 b (1-m) / T
  const json& measured = j["zwidth"]["measured"];
  ASSERT_GE(measured.size(), 4u) << r.out;
  for (const json& m : measured) {
    const double analytic = m["analytic_stiffness"].get<double>();
    EXPECT_NEAR(m["stiffness"].get<double>(), analytic, 1e-3 * analytic) << m.dump();
  }
  const json& n = j["nyquist"];
  EXPECT_EQ(n["theta"].size(), 800u);
  EXPECT_EQ(n["re"].size(), 800u);
  EXPECT_EQ(n["tsai_colgate"], true);
}

TEST(CliCurves, AFailingWallIsMarkedAndACouplingsPoleLeavesNoNyquistPlot) {
  const ProcessResult r = run_process({hapticd_binary(), "curves", "--no-measure", "--config",
                                       source_dir() + "/config/coupling-example.yaml"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["configured"]["pass"], true);
  EXPECT_TRUE(j["zwidth"]["measured"].empty());
  EXPECT_TRUE(j["nyquist"]["theta"].empty());
  EXPECT_NE(j["nyquist"]["note"].get<std::string>().find("pole at z = 1"), std::string::npos);
  const ProcessResult bare =
      run_process({hapticd_binary(), "curves", "--no-measure", "--set", "wall.stiffness=9000"});
  ASSERT_EQ(bare.exit_code, 0) << bare.err;
  EXPECT_EQ(json::parse(bare.out)["configured"]["pass"], false);
  EXPECT_EQ(run_process({hapticd_binary(), "curves", "--set", "wall.stiffness=-1"}).exit_code, 2);
}

}  // namespace
}  // namespace hapticd::testing
