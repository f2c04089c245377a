// libFuzzer target: each line of the input is one `--set` argument (key.path=value). They are
// applied to the embedded default, as `hapticd check --set ...` does without --config, or,
// when the first line is "---", to an empty document, where every section comes from --set
// alone; the load then goes through the gate. Invariants: support/config_oracle.h.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "config/config_loader.h"
#include "support/config_oracle.h"
#include "wiring/registry.h"

namespace {

namespace config = hapticd::config;
namespace fuzz = hapticd::fuzz;

// A malformed argument is checked and left out, so the arguments after it still run (the CLI
// would stop at it with exit 2, which leaves nothing to explore).
std::vector<config::Override> parse_lines(std::string_view input) {
  std::vector<config::Override> overrides;
  while (!input.empty()) {
    const std::size_t eol = input.find('\n');
    const std::string_view arg = input.substr(0, eol);
    input.remove_prefix(eol == std::string_view::npos ? input.size() : eol + 1);
    try {
      overrides.push_back(config::parse_override(arg));
    } catch (const config::ConfigError& e) {
      fuzz::check_config_error(e, {"--set "});
    }
  }
  return overrides;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view input(reinterpret_cast<const char*>(data), size);
  // One base per input: loading and gating both would halve the executions per second.
  constexpr std::string_view kEmptyBase = "---\n";
  const bool empty_base = input.starts_with(kEmptyBase);
  if (empty_base) input.remove_prefix(kEmptyBase.size());
  const std::vector<config::Override> overrides = parse_lines(input);
  const config::DriverSchemas& drivers = hapticd::wiring::driver_schemas();
  if (empty_base) {
    fuzz::check_load_then_gate(
        [&] { return config::load_config_text("", "empty.yaml", overrides, "/fuzz", drivers); },
        {"empty.yaml:", "--set "});
  } else {
    fuzz::check_load_then_gate([&] { return config::load_embedded_default(overrides, drivers); },
                               {"config/sim.yaml (embedded):", "--set "});
  }
  return 0;
}
