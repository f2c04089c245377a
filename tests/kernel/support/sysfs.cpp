#include "sysfs.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <thread>

#include "unique_fd.h"

namespace hapticd::kernel_test {

void throw_errno(const std::string& what) {
  throw KernelFacilityError(what + ": " + std::strerror(errno));
}

void require_path(const std::string& path, const std::string& facility) {
  if (path_exists(path)) return;
  throw KernelFacilityError(facility + " is not available (" + path +
                            " is missing). These tests run inside hapticd's kernel test "
                            "machine: `ctest -L kernel`, or tools/kernel-vm/run -- BINARY");
}

std::string read_text(const std::string& path) {
  UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd) throw_errno("open " + path);
  std::string text;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buf, sizeof buf);
    if (n < 0) throw_errno("read " + path);
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  while (!text.empty() && text.back() == '\n') text.pop_back();
  return text;
}

// One write() call: sysfs and configfs take an attribute's value in a single write.
void write_text(const std::string& path, const std::string& text) {
  UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CLOEXEC));
  if (!fd) throw_errno("open " + path);
  const ssize_t n = ::write(fd.get(), text.data(), text.size());
  if (n < 0) throw_errno("write '" + text + "' to " + path);
  if (static_cast<std::size_t>(n) != text.size()) {
    throw KernelFacilityError("short write of '" + text + "' to " + path);
  }
}

bool path_exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

void make_dir(const std::string& path) {
  if (::mkdir(path.c_str(), 0755) != 0) throw_errno("mkdir " + path);
}

void remove_dir(const std::string& path) noexcept { ::rmdir(path.c_str()); }

void wait_until(const std::function<bool()>& predicate, std::chrono::milliseconds timeout,
                const std::string& what) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!predicate()) {
    if (std::chrono::steady_clock::now() > deadline) {
      throw KernelFacilityError("timed out after " + std::to_string(timeout.count()) +
                                " ms waiting for " + what);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

std::vector<std::string> list_dir(const std::string& path) {
  std::vector<std::string> names;
  DIR* dir = ::opendir(path.c_str());
  if (dir == nullptr) return names;
  while (const dirent* entry = ::readdir(dir)) {
    const std::string name = entry->d_name;
    if (name != "." && name != "..") names.push_back(name);
  }
  ::closedir(dir);
  std::sort(names.begin(), names.end());
  return names;
}

std::string hex4(std::uint16_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "%04x", value);
  return text;
}

}  // namespace hapticd::kernel_test
