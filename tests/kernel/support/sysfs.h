// Small file helpers for sysfs and configfs, shared by the kernel test fixtures. Every failure
// throws KernelFacilityError naming the path and the errno text, so a test that runs outside
// the kernel test machine fails with a reason instead of a crash.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticd::kernel_test {

class KernelFacilityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "what: strerror(errno)" as an exception.
[[noreturn]] void throw_errno(const std::string& what);

// Throws unless PATH exists, saying which kernel facility is missing and how the tests are
// meant to run (inside tools/kernel-vm, e.g. through `ctest -L kernel`).
void require_path(const std::string& path, const std::string& facility);

std::string read_text(const std::string& path);  // whole file, trailing newline removed
void write_text(const std::string& path, const std::string& text);
bool path_exists(const std::string& path);
void make_dir(const std::string& path);
void remove_dir(const std::string& path) noexcept;  // best effort, for destructors

// Polls PREDICATE every millisecond until it holds; throws naming WHAT after TIMEOUT.
void wait_until(const std::function<bool()>& predicate, std::chrono::milliseconds timeout,
                const std::string& what);

// Entries of a directory (no "." and ".."), sorted; empty when it does not exist.
std::vector<std::string> list_dir(const std::string& path);

// Where configfs keeps USB gadgets (libcomposite), and a USB id as sysfs writes it: "1209".
inline constexpr const char* kUsbGadgets = "/sys/kernel/config/usb_gadget";
std::string hex4(std::uint16_t value);

}  // namespace hapticd::kernel_test
