// YAML -> validated Config. Every problem in a document is collected and reported at once,
// each as "SOURCE:LINE: key.path: what is wrong" (or "--set ARG: key.path: ..." for a value
// that came from the command line), so a person can fix them all in one edit.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "config/driver_schema.h"

namespace hapticd::config {

// One --set key.path=value. `value` is parsed as YAML (so lists and booleans work); `text`
// is the argument as the user typed it, used to prefix messages about that value.
struct Override {
  std::string key_path;
  std::string value;
  std::string text;
};

// A failed load reports at most this many messages, then one line counting the rest: a
// person fixes the first ones and reloads.
inline constexpr std::size_t kMaxMessages = 100;

// Every message of one failed load; what() is the messages joined with '\n'.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<std::string> messages);
  const std::vector<std::string>& messages() const noexcept { return messages_; }

 private:
  std::vector<std::string> messages_;
};

// "a.b.c=value" -> {"a.b.c", "value", arg}. Throws ConfigError
// "--set ARG: expected key.path=value" when there is no '=' or a key segment is empty.
Override parse_override(std::string_view arg);

// Parses and validates a configuration held in memory (the config library does no file
// I/O: the service reads files). `source_name` prefixes messages ("sim.yaml:12: ..."),
// `base_dir` resolves relative paths inside it (device.sim.operator.log), and device.driver
// must name one of `drivers`, whose own section device.<driver> that driver's code reads.
Config load_config_text(std::string_view yaml, const std::string& source_name,
                        const std::vector<Override>& overrides = {},
                        const std::string& base_dir = ".",
                        const DriverSchemas& drivers = sim_driver_only());

// Not RT-safe. The configuration document `effective_yaml` (a Config's, already validated)
// with one key set to `o.value`, as a --set would write it, for a setting the service changed
// in the typed Config itself (safety.gate: derate): the document a tick log records then holds
// what ran. Nothing is validated again; throws ConfigError when the key cannot be set.
std::string with_setting(std::string_view effective_yaml, const Override& o);

// config/sim.yaml as compiled into the binary (source name "config/sim.yaml (embedded)").
Config load_embedded_default(const std::vector<Override>& overrides = {},
                             const DriverSchemas& drivers = sim_driver_only());
std::string_view embedded_default_yaml() noexcept;

}  // namespace hapticd::config
