// The installed service as a packager and an operator see it: `cmake --install` to a fresh
// prefix gives stripped binaries, a template unit generated for that prefix that
// systemd-analyze verifies (man page included) and rates at most 2.0 for exposure, the
// sysusers.d entry of its user, its one udev rule, and a man page `man` finds.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "process.h"

namespace hapticd::testing {
namespace {

// `cmake --install` of the build into `prefix`.
ProcessResult install_to(const std::string& prefix) {
  return run_process(
      {"/bin/sh", "-c", "cmake --install '" + build_dir() + "' --prefix '" + prefix + "' 2>&1"});
}

TEST(Install, GivesAStrippedBinaryAManPageAndAUnitThatVerifies) {
  const std::string prefix = temp_path("prefix");
  const ProcessResult inst = install_to(prefix);
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

  EXPECT_TRUE(std::filesystem::exists(prefix + "/bin/hapticctl")) << inst.out;
  const std::string unit = prefix + "/lib/systemd/system/hapticd@.service";
  ASSERT_TRUE(std::filesystem::exists(unit)) << inst.out;
  EXPECT_FALSE(std::filesystem::exists(prefix + "/lib/systemd/system/hapticd.service"))
      << "the template's default instance replaces the plain unit";
  const std::string text = read_file(unit);
  EXPECT_TRUE(has(text, "ExecStart=" + bin + " run --config " + prefix +
                            "/etc/hapticd/%i.yaml --socket ${RUNTIME_DIRECTORY}/control.sock"))
      << text;
  EXPECT_TRUE(has(text, "DefaultInstance=hapticd")) << text;
  EXPECT_FALSE(has(text, "http")) << "no URL that does not exist";
  EXPECT_TRUE(std::filesystem::exists(prefix + "/etc/hapticd/hapticd.yaml"))
      << "the default instance's configuration";

  const std::string manpath = "MANPATH=" + prefix + "/share/man";
  const ProcessResult man = run_process({"/bin/sh", "-c", manpath + " man -w hapticd"});
  EXPECT_EQ(man.exit_code, 0);
  EXPECT_EQ(man.out, prefix + "/share/man/man1/hapticd.1\n");

  // Without --man=no: the Documentation= man page must exist too.
  const ProcessResult verify =
      run_process({"/bin/sh", "-c", manpath + " systemd-analyze verify '" + unit + "' 2>&1"});
  EXPECT_EQ(verify.exit_code, 0) << verify.out;
  EXPECT_FALSE(has(verify.out, "hapticd@")) << "systemd-analyze complains:\n" << verify.out;
}

// The template unit's hardening as systemd rates it: exposure at most 2.0 ("OK"), with the
// capabilities, devices and scheduling a servo needs and nothing more.
TEST(Install, TheTemplateUnitsExposureIsAtMostTwo) {
  const std::string prefix = temp_path("prefix-security");
  const ProcessResult inst = install_to(prefix);
  ASSERT_EQ(inst.exit_code, 0) << inst.out;
  const std::string unit = prefix + "/lib/systemd/system/hapticd@.service";
  const ProcessResult r = run_process(
      {"/bin/sh", "-c", "systemd-analyze security --offline=true --no-pager '" + unit + "' 2>&1"});
  const std::string key = "Overall exposure level for hapticd@";
  const auto at = r.out.find(key);
  ASSERT_NE(at, std::string::npos) << r.out;
  const auto colon = r.out.find(": ", at);
  ASSERT_NE(colon, std::string::npos) << r.out;
  const double exposure = std::stod(r.out.substr(colon + 2));
  EXPECT_LE(exposure, 2.0) << r.out;
  const std::string text = read_file(unit);
  for (const char* must :
       {"User=hapticd", "CapabilityBoundingSet=CAP_SYS_NICE CAP_IPC_LOCK", "DevicePolicy=closed",
        "RuntimeDirectory=hapticd/%i", "ProtectKernelTunables=yes",
        "SystemCallFilter=@system-service", "RestrictAddressFamilies=AF_UNIX AF_CAN AF_NETLINK"}) {
    EXPECT_TRUE(has(text, must)) << must;
  }
}

// The system user the unit runs as, and the udev rule that gives its group the PM QoS node.
TEST(Install, CreatesTheSystemUserAndTheUdevRules) {
  const std::string prefix = temp_path("prefix-users");
  const ProcessResult inst = install_to(prefix);
  ASSERT_EQ(inst.exit_code, 0) << inst.out;
  const std::string sysusers = prefix + "/lib/sysusers.d/hapticd.conf";
  ASSERT_TRUE(std::filesystem::exists(sysusers));
  const std::string root = temp_path("sysroot");
  std::filesystem::create_directories(root + "/etc");
  const ProcessResult r = run_process(
      {"/bin/sh", "-c", "systemd-sysusers --root='" + root + "' '" + sysusers + "' 2>&1"});
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string passwd = read_file(root + "/etc/passwd");
  EXPECT_TRUE(has(passwd, "hapticd:x:")) << passwd;
  EXPECT_TRUE(has(passwd, ":/usr/sbin/nologin")) << "a system user with no login shell";
  EXPECT_TRUE(has(read_file(root + "/etc/group"), "hapticd:x:"));
  // The one installed rule (install_manifest_test.cpp holds the whole list to the docs); the
  // devices' rules are an instance's, written by `hapticd udev-rules`.
  EXPECT_TRUE(has(read_file(prefix + "/lib/udev/rules.d/60-hapticd-rt.rules"),
                  "KERNEL==\"cpu_dma_latency\", SUBSYSTEM==\"misc\", GROUP=\"hapticd\""));
}

}  // namespace
}  // namespace hapticd::testing
