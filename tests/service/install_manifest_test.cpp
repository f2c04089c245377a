// What installing hapticd changes on a host is what docs/operations.md says it is ("What
// installing changes on the host"): `cmake --install` for the prefix /usr into a DESTDIR puts
// exactly the files of its table there, and the installed udev rules are exactly the rules of
// its udev block. And no installed rule touches a network interface, a GPIO or PWM chip, a HID
// or USB device, or runs a program: those are an instance's (`hapticd udev-rules`).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "process.h"

namespace hapticd::testing {
namespace {

namespace fs = std::filesystem;

struct Manifest {
  std::set<std::string> files;
  std::set<std::string> rules;
};

// The section's table rows "| `/path` | ... |" and its ```udev block.
Manifest documented() {
  std::istringstream in(read_file(source_dir() + "/docs/operations.md"));
  Manifest m;
  bool in_section = false, in_block = false;
  const std::regex row(R"(^\| `(/[^`]+)` \|)");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## What installing changes on the host";
    if (!in_section) continue;
    std::smatch match;
    if (in_block) {
      if (line == "```") {
        in_block = false;
      } else if (!line.empty()) {
        m.rules.insert(line);
      }
    } else if (line == "```udev") {
      in_block = true;
    } else if (std::regex_search(line, match, row)) {
      m.files.insert(match[1]);
    }
  }
  return m;
}

// The rules of a rules file: every line that is not a comment, continuations joined.
std::vector<std::string> rules_of(const std::string& path) {
  std::vector<std::string> rules;
  std::istringstream in(read_file(path));
  std::string rule;
  for (std::string line; std::getline(in, line);) {
    if (rule.empty() && (line.empty() || line[0] == '#')) continue;
    const bool continued = !line.empty() && line.back() == '\\';
    rule += continued ? line.substr(0, line.size() - 1) : line;
    if (!continued) {
      rules.push_back(rule);
      rule.clear();
    }
  }
  return rules;
}

TEST(Install, ChangesExactlyWhatDocsOperationsSaysAndNoDeviceOfTheHost) {
  const Manifest doc = documented();
  ASSERT_FALSE(doc.files.empty()) << "docs/operations.md has no table of installed files";
  ASSERT_FALSE(doc.rules.empty()) << "docs/operations.md has no ```udev block";

  const std::string destdir = temp_path("destdir");
  const ProcessResult inst = run_process(
      {"/bin/sh", "-c",
       "DESTDIR='" + destdir + "' cmake --install '" + build_dir() + "' --prefix /usr 2>&1"});
  ASSERT_EQ(inst.exit_code, 0) << inst.out;

  Manifest installed;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(destdir)) {
    if (e.is_directory()) continue;
    const std::string path = e.path().string().substr(destdir.size());
    installed.files.insert(path);
    if (e.path().extension() != ".rules") continue;
    for (const std::string& rule : rules_of(e.path().string())) installed.rules.insert(rule);
  }
  EXPECT_EQ(installed.files, doc.files) << "installed (left) against docs/operations.md (right)";
  EXPECT_EQ(installed.rules, doc.rules) << "installed (left) against docs/operations.md (right)";

  for (const std::string& rule : installed.rules) {
    for (const char* device : {"\"net\"", "\"gpio\"", "\"pwm\"", "\"hidraw\"", "\"usb\"",
                               "gpiochip", "pwmchip", "can"}) {
      EXPECT_FALSE(has(rule, device)) << "an installed rule for every " << device << ": " << rule;
    }
    EXPECT_FALSE(has(rule, "RUN")) << "an installed rule runs a program on the host: " << rule;
  }

#if HAPTICD_TEST_WITH_CAN
  // The installed binary writes an instance's rules: one interface, by name.
  const ProcessResult rules = run_process({destdir + "/usr/bin/hapticd", "udev-rules", "--config",
                                           source_dir() + "/config/can-cia402.yaml"});
  EXPECT_EQ(rules.exit_code, 0) << rules.err;
  EXPECT_TRUE(has(rules.out, "/etc/udev/rules.d/70-hapticd-can-cia402.rules")) << rules.out;
  EXPECT_TRUE(has(rules.out, "KERNEL==\"can0\", ATTR{type}==\"280\"")) << rules.out;
#endif
}

#if HAPTICD_TEST_WITH_GPIO
TEST(Install, AnInstanceRuleARuleCannotMatchExactlyIsAUsageError) {
  const ProcessResult r =
      run_process({hapticd_binary(), "udev-rules", "--config", source_dir() + "/config/gpio.yaml",
                   "--set", "device.gpio.chip=pinctrl-bcm2835"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r.err, "device.gpio.chip: 'pinctrl-bcm2835' is not a chip's kernel name"))
      << r.err;
  EXPECT_TRUE(r.out.empty()) << "no half-written rules file: " << r.out;
}
#endif

}  // namespace
}  // namespace hapticd::testing
