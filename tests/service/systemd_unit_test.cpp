#include <gtest/gtest.h>

#include <fstream>

#include "process.h"

namespace hapticd::testing {
namespace {

TEST(SystemdUnit, VerifiesOffline) {
  if (run_process({"/bin/sh", "-c", "command -v systemd-analyze"}).exit_code != 0) {
    GTEST_SKIP() << "systemd-analyze not installed (Debian package 'systemd'): unit not verified";
  }
  // Point ExecStart at the binary just built: verify checks that the command exists.
  std::string unit = read_file(source_dir() + "/systemd/hapticd.service");
  const std::string installed = "/usr/local/bin/hapticd";
  ASSERT_NE(unit.find(installed), std::string::npos);
  unit.replace(unit.find(installed), installed.size(), hapticd_binary());
  const std::string path = temp_path("hapticd.service");
  std::ofstream(path) << unit;
  const ProcessResult r =
      run_process({"/bin/sh", "-c", "systemd-analyze verify --man=no " + path + " 2>&1"});
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(r.out.find("hapticd.service"), std::string::npos) << "systemd-analyze complains:\n"
                                                              << r.out;
}

}  // namespace
}  // namespace hapticd::testing
