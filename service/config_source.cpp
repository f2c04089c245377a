#include "service/config_source.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <system_error>

#include "config/config_loader.h"
#include "control/derived_check.h"
#include "wiring/registry.h"

namespace hapticd::service {
// The config library parses text; reading the file is the service's (it owns all I/O).
std::string read_config_file(const std::string& path) {
  const auto fail = [&](int err) {
    return config::ConfigError({path + ": cannot read: " + std::system_category().message(err)});
  };
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw fail(errno);
  std::string text;
  char buf[16384];
  while (true) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw fail(err);
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return text;
}

config::Config load_config_text_checked(const std::string& text, const std::string& source,
                                        const std::string& base_dir,
                                        const std::vector<std::string>& sets) {
  std::vector<config::Override> overrides;
  for (const std::string& s : sets) overrides.push_back(config::parse_override(s));
  config::Config cfg =
      config::load_config_text(text, source, overrides, base_dir, wiring::driver_schemas());
  control::check_derived_quantities(cfg);
  return cfg;
}

void require_one_joint(const config::Config& cfg, const std::string& command) {
  const int n = kinematics::joint_count(cfg.device.kinematics);
  if (n == 1) return;
  throw config::ConfigError(
      {cfg.locate("device.kinematics") + ": device.kinematics: `hapticd " + command +
       "` works on the wall of one joint; kind " +
       kinematics::kind_name(cfg.device.kinematics.kind) + " has " + std::to_string(n) +
       " (for several axes `hapticd check` proves the walls and `hapticd run` drives them: "
       "docs/kinematics.md)"});
}

config::Config load_config(const ConfigOptions& options) {
  std::vector<config::Override> overrides;
  overrides.reserve(options.sets.size());
  for (const std::string& s : options.sets) overrides.push_back(config::parse_override(s));
  if (!options.path.empty()) {
    std::string base_dir = std::filesystem::path(options.path).parent_path().string();
    if (base_dir.empty()) base_dir = ".";
    return load_config_text_checked(read_config_file(options.path), options.path, base_dir,
                                    options.sets);
  }
  config::Config cfg = config::load_embedded_default(overrides, wiring::driver_schemas());
  control::check_derived_quantities(cfg);
  return cfg;
}

}  // namespace hapticd::service
