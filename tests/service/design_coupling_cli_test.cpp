// `hapticd design-coupling` on input it must refuse or need not design for, and `check`
// naming it on a refused wall: cheap, so they run in every stage (the designs themselves are
// in design_coupling_walls_test.cpp, main stage only).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "design_coupling_support.h"
#include "process.h"

namespace hapticd::testing {
namespace {

TEST(DesignCoupling, RefusesBadInputWithExit2) {
  const auto refused = [](const std::vector<std::string>& extra, const std::string& says) {
    const ProcessResult r = run_process(
        concat({hapticd_binary(), "design-coupling", "--config", coupling_example()}, extra));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
  };
  refused({"--order", "0"}, "order must be 1 to 8");
  refused({"--order", "1000000"}, "order must be 1 to 8");
  refused({"--weight", "loud"}, "--weight must be felt or configured");
  refused({"--felt-from-hz", "30"}, "below the Nyquist frequency");
  refused({"--felt-from-hz", "nan"}, "--felt-from-hz");
  refused({"--max-steps", "0"}, "--max-steps");
  refused({"--set", "wall.discretization=tustin"}, "design for backward");
  refused({"--set", "safety.operator_passivity_shortage=20"}, "must be > 0");
}

// A wall the gate passes bare gets no coupling: every one Theorem 1 admits has H(1) = 0, so it
// would only make the wall yield. Exit 0, said on stdout, and nothing to paste.
TEST(DesignCoupling, DesignsNothingForAWallThatPassesBare) {
  const std::vector<std::string> soft{"--config", coupling_example(),   "--set", "wall.coupling=",
                                      "--set",    "wall.stiffness=100", "--set", "wall.damping=0"};
  const ProcessResult text = run_process(concat({hapticd_binary(), "design-coupling"}, soft));
  EXPECT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("passes the gate without a coupling"), std::string::npos) << text.out;
  EXPECT_EQ(text.out.find("paste into the configuration"), std::string::npos) << text.out;
  EXPECT_EQ(text.err.find("design-coupling: step"), std::string::npos) << text.err;  // no search
  const ProcessResult j =
      run_process(concat({hapticd_binary(), "design-coupling", "--json"}, soft));
  ASSERT_EQ(j.exit_code, 0) << j.err;
  const nlohmann::json d = nlohmann::json::parse(j.out);
  EXPECT_EQ(d["status"], "not needed");
  EXPECT_EQ(d.count("coupling"), 0u);
  EXPECT_EQ(d["bare_wall"]["static_stiffness"].get<double>(), 100.0);
}

TEST(DesignCoupling, CheckNamesItOnARefusedWall) {
  const ProcessResult r = run_process(
      {hapticd_binary(), "check", "--config", coupling_example(), "--set", "wall.coupling="});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("hapticd design-coupling"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace hapticd::testing
