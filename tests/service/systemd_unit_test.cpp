// The installed service as a packager and an operator see it: `cmake --install` to a fresh
// prefix gives a stripped binary, a unit generated for that prefix that systemd-analyze
// verifies (man page included), and a man page `man` finds.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "process.h"

namespace hapticd::testing {
namespace {

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Install, GivesAStrippedBinaryAManPageAndAUnitThatVerifies) {
  const std::string prefix = temp_path("prefix");
  const ProcessResult inst = run_process(
      {"/bin/sh", "-c", "cmake --install '" + build_dir() + "' --prefix '" + prefix + "' 2>&1"});
  ASSERT_EQ(inst.exit_code, 0) << inst.out;

  const std::string bin = prefix + "/bin/hapticd";
  ASSERT_TRUE(std::filesystem::exists(bin)) << inst.out;
  const ProcessResult file = run_process({"/bin/sh", "-c", "file -b '" + bin + "'"});
  if (file.exit_code == 0) {
    EXPECT_TRUE(has(file.out, "stripped") && !has(file.out, "not stripped")) << file.out;
  }
#ifndef HAPTICD_SANITIZED  // a sanitizer's runtime and checks take a stripped binary past 30 MB
  EXPECT_LT(std::filesystem::file_size(bin), 20u << 20) << "a stripped binary is a few MB";
#endif

  const std::string unit = prefix + "/lib/systemd/system/hapticd.service";
  ASSERT_TRUE(std::filesystem::exists(unit)) << inst.out;
  const std::string text = read_file(unit);
  EXPECT_TRUE(
      has(text, "ExecStart=" + bin + " run --config " + prefix + "/etc/hapticd/hapticd.yaml"))
      << text;
  EXPECT_FALSE(has(text, "http")) << "no URL that does not exist";
  EXPECT_TRUE(std::filesystem::exists(prefix + "/etc/hapticd/hapticd.yaml"));

  const std::string manpath = "MANPATH=" + prefix + "/share/man";
  const ProcessResult man = run_process({"/bin/sh", "-c", manpath + " man -w hapticd"});
  EXPECT_EQ(man.exit_code, 0);
  EXPECT_EQ(man.out, prefix + "/share/man/man1/hapticd.1\n");

  // Without --man=no: the Documentation= man page must exist too.
  const ProcessResult verify =
      run_process({"/bin/sh", "-c", manpath + " systemd-analyze verify '" + unit + "' 2>&1"});
  EXPECT_EQ(verify.exit_code, 0) << verify.out;
  EXPECT_FALSE(has(verify.out, "hapticd.service")) << "systemd-analyze complains:\n" << verify.out;
}

}  // namespace
}  // namespace hapticd::testing
