#include "sim/peers/endpoint_verdict.h"

namespace hapticd::sim {

std::string sysfs_driver_of(const std::filesystem::path& device) {
  std::error_code ec;
  const std::filesystem::path driver = std::filesystem::read_symlink(device / "driver", ec);
  return ec ? std::string() : driver.filename().string();
}

}  // namespace hapticd::sim
