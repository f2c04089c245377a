#include "design_coupling_support.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "process.h"

namespace hapticd::testing {
namespace {

std::string list(const nlohmann::json& a) {
  std::string s = "[";
  for (std::size_t i = 0; i < a.size(); ++i) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", a[i].get<double>());
    s += (i ? "," : "") + std::string(buf);
  }
  return s + "]";
}

}  // namespace

nlohmann::json design_coupling_json(const std::vector<std::string>& extra) {
  std::vector<std::string> args{hapticd_binary(), "design-coupling", "--json"};
  args.insert(args.end(), extra.begin(), extra.end());
  const ProcessResult r = run_process(args);
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  // A progress line per outer step (none at order 1: the family alone needs no SDP).
  int lines = 0;
  for (std::size_t at = 0; (at = r.err.find("design-coupling: step ", at)) != std::string::npos;
       ++at) {
    ++lines;
  }
  EXPECT_EQ(lines, j["steps"].get<int>()) << r.err;
  j["exit_code"] = r.exit_code;
  return j;
}

std::vector<std::string> pasted_coupling(const nlohmann::json& d) {
  return {"--set", "wall.coupling.numerator=" + list(d["coupling"]["numerator"]), "--set",
          "wall.coupling.denominator=" + list(d["coupling"]["denominator"])};
}

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace hapticd::testing
