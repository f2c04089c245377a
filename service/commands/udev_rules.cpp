#include "service/commands/udev_rules.h"

#include <filesystem>

#include "config/config_loader.h"
#include "drivers/udev_rules.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "wiring/registry.h"

namespace hapticd::service {

std::string instance_udev_rules(const config::Config& cfg, const std::string& instance) {
  drivers::UdevRules out(cfg, kServiceGroup);
  out.comment("udev rules of hapticd instance " + instance +
              ", written by `hapticd udev-rules` from " + cfg.source_name +
              ". Install as /etc/udev/rules.d/70-hapticd-" + instance +
              ".rules, then `udevadm control --reload` and `udevadm trigger --action=add` "
              "(docs/operations.md). When the configuration changes, write them again rather "
              "than edit them.");
  const wiring::DriverEntry& driver = wiring::find_driver(cfg.device.driver);
  if (driver.udev_rules != nullptr) {
    driver.udev_rules(cfg, out);
  } else {
    out.comment("device.driver " + cfg.device.driver + ": no device, nothing for udev to do.");
  }
  return out.text();
}

int udev_rules_command(const ConfigOptions& options, std::string instance) {
  const config::Config cfg = load_config(options);
  if (instance.empty()) {
    instance =
        options.path.empty() ? "hapticd" : std::filesystem::path(options.path).stem().string();
  }
  if (!drivers::udev_literal(instance)) {
    throw config::ConfigError(
        {"--instance: '" + instance + "' is not a plain instance name (letters, digits, _ - . :)"});
  }
  return write_stdout(instance_udev_rules(cfg, instance)) ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
