#include "service/config_source.h"

#include "config/config_loader.h"
#include "control/derived_check.h"

namespace hapticd::service {

config::Config load_config(const ConfigOptions& options) {
  std::vector<config::Override> overrides;
  overrides.reserve(options.sets.size());
  for (const std::string& s : options.sets) overrides.push_back(config::parse_override(s));
  config::Config cfg = options.path.empty() ? config::load_embedded_default(overrides)
                                            : config::load_config_file(options.path, overrides);
  control::check_derived_quantities(cfg);
  return cfg;
}

}  // namespace hapticd::service
