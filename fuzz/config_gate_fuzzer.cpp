// libFuzzer target: the input as the text of a YAML configuration file, loaded as `--config`
// loads one, then the gate as `hapticd check` runs it. Invariants: support/config_oracle.h.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config/config_loader.h"
#include "support/config_oracle.h"
#include "wiring/registry.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view yaml(reinterpret_cast<const char*>(data), size);
  // The base directory only resolves device.sim.operator.log; loading never opens that file.
  // Every registered driver reads its own section, as in the daemon.
  hapticd::fuzz::check_load_then_gate(
      [&] {
        return hapticd::config::load_config_text(yaml, "fuzz.yaml", {}, "/fuzz",
                                                 hapticd::wiring::driver_schemas());
      },
      {"fuzz.yaml:"});
  return 0;
}
