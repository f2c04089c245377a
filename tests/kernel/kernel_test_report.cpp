// The host side of one kernel test in ctest. gtest_discover_tests treats this program as the
// test binaries' CROSSCOMPILING_EMULATOR: it lists tests as `report BINARY --gtest_list_tests`
// and runs each as `report BINARY --gtest_filter=Suite.Name`. Listing needs no kernel
// facility, so that runs BINARY on the host; a test is answered from the gtest JSON that the
// single boot of the "kernel.vm" test wrote for BINARY in HAPTICD_KERNEL_RESULTS, so every
// kernel test is its own ctest result while the guest boots once for all of them. The tests
// under a real systemd (tests/systemd) have their own copy of this program, built with their
// own results directory, boot test and label.
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::string kResults = HAPTICD_KERNEL_RESULTS;
#ifndef HAPTICD_KERNEL_LABEL
#define HAPTICD_KERNEL_LABEL "kernel"
#endif
const std::string kBootTest = "kernel.vm";  // the ctest test that boots the guests
const std::string kLabel = HAPTICD_KERNEL_LABEL;

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool exists(const std::string& path, struct stat* st = nullptr) {
  struct stat local {};
  return ::stat(path.c_str(), st != nullptr ? st : &local) == 0;
}

std::string last_lines(const std::string& text, std::size_t count) {
  std::size_t pos = text.size();
  for (std::size_t n = 0; pos > 0 && n <= count; ++n) pos = text.rfind('\n', pos - 1);
  return pos == std::string::npos ? text : text.substr(pos + 1);
}

// Why there is no JSON for BINARY: it crashed or hung in the guest, or the guest never ran it.
int report_missing(const std::string& name) {
  const std::string base = kResults + "/" + name;
  if (exists(base + ".status")) {
    std::cout << "FAILED: " << name << " ended with status " << read_file(base + ".status")
              << "in the kernel test machine before writing its results. Its output (" << base
              << ".log) ends:\n"
              << last_lines(read_file(base + ".log"), 30) << "\n";
  } else {
    std::cout << "FAILED: no results for " << name << " in " << kResults << ": the " << kBootTest
              << " test, which boots the guest once for all of these tests, did not run it (run "
              << "the tests labelled " << kLabel << ": `ctest -L " << kLabel << "`).\n";
  }
  return 1;
}

bool skipped(const nlohmann::json& test) {
  return test.value("status", "") == "NOTRUN" || test.value("result", "") == "SKIPPED";
}

nlohmann::json failures_of(const nlohmann::json& test) {
  return test.value("failures", nlohmann::json::array());
}

void print_failures(const nlohmann::json& failures) {
  for (const auto& failure : failures) std::cout << failure.value("failure", "") << "\n\n";
}

// The test FULL_NAME in a binary's gtest JSON at PATH, or null if there is no such file or test.
nlohmann::json find_test(const std::string& path, const std::string& full_name) {
  if (!exists(path)) return nullptr;
  const auto results = nlohmann::json::parse(read_file(path));
  for (const auto& suite : results.at("testsuites")) {
    for (const auto& test : suite.at("testsuite")) {
      if (suite.at("name").get<std::string>() + "." + test.at("name").get<std::string>() ==
          full_name) {
        return test;
      }
    }
  }
  return nullptr;
}

// A test that failed in the guest ran once more there (tools/kernel-vm/test-suite: the
// emulator stalls the guest on a loaded host); it passes only if that second run passed, and
// says so with the first run's failure. The marker line is what the quick start's summary
// lists.
int report_test(const nlohmann::json& test, const std::string& full_name, const std::string& base) {
  if (skipped(test)) {
    std::cout << "[  SKIPPED ] " << full_name << " (in the kernel test machine)\n";
    return 0;
  }
  const auto failures = failures_of(test);
  if (failures.empty()) {
    std::cout << "[       OK ] " << full_name << " (" << test.value("time", "?")
              << " in the kernel test machine)\n";
    return 0;
  }
  print_failures(failures);
  const nlohmann::json again = find_test(base + ".rerun.json", full_name);
  if (again.is_object() && !skipped(again) && failures_of(again).empty()) {
    std::cout << "[       OK ] " << full_name << " (" << again.value("time", "?")
              << " in the kernel test machine)\nkernel test passed on its second run: " << full_name
              << "; its first run failed as above (" << base << ".log)\n";
    return 0;
  }
  if (again.is_object()) {
    std::cout << "and again on its second run (" << base << ".rerun.log):\n";
    print_failures(failures_of(again));
  }
  std::cout << "[  FAILED  ] " << full_name << " in the kernel test machine; the binary's "
            << "whole output is in " << base << ".log\n";
  return 1;
}

int report(const std::string& binary, const std::string& filter) {
  if (const char* on = std::getenv("HAPTICD_KERNEL_TESTS");
      on != nullptr && !std::strcmp(on, "0")) {
    std::cout << "[  SKIPPED ] " << filter << ": kernel tests are off (HAPTICD_KERNEL_TESTS=0)\n";
    return 0;
  }
  const std::string name = binary.substr(binary.rfind('/') + 1);
  const std::string json_path = kResults + "/" + name + ".json";
  struct stat json_stat {
  }, binary_stat{};
  if (!exists(json_path, &json_stat)) return report_missing(name);
  if (exists(binary, &binary_stat) && binary_stat.st_mtime > json_stat.st_mtime) {
    std::cout << "FAILED: " << json_path << " is older than " << binary
              << ": the results are from another build (run `ctest -L " << kLabel << "`).\n";
    return 1;
  }
  const nlohmann::json test = find_test(json_path, filter);
  if (test.is_null()) {
    std::cout << "FAILED: " << filter << " is not in " << json_path << "\n";
    return 1;
  }
  return report_test(test, filter, kResults + "/" + name);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: " << argv[0] << " TEST_BINARY --gtest_list_tests|--gtest_filter=NAME\n";
    return 2;
  }
  const std::string binary = argv[1];
  std::string filter;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--gtest_list_tests")) {
      ::execv(binary.c_str(), argv + 1);
      std::cerr << "cannot run " << binary << ": " << std::strerror(errno) << "\n";
      return 127;
    }
    if (!std::strncmp(argv[i], "--gtest_filter=", 15)) filter = argv[i] + 15;
  }
  if (filter.empty()) {
    std::cerr << argv[0] << ": no --gtest_filter=Suite.Name\n";
    return 2;
  }
  try {
    return report(binary, filter);
  } catch (const std::exception& e) {
    std::cout << "FAILED: cannot read the results for " << filter << ": " << e.what() << "\n";
    return 1;
  }
}
