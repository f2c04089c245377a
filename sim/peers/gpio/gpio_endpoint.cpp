#include "sim/peers/gpio/gpio_endpoint.h"

#include <filesystem>

namespace hapticd::sim::gpio {
namespace {

namespace fs = std::filesystem;
using Kind = EndpointVerdict::Kind;

}  // namespace

GpioChipFacts read_gpio_chip(const std::string& chip_dir) {
  GpioChipFacts facts;
  std::error_code ec;
  const fs::path dir = fs::canonical(chip_dir, ec);
  if (ec || !fs::is_directory(dir, ec)) return facts;
  facts.exists = true;
  const fs::path subsystem = fs::canonical(dir / "subsystem", ec);
  facts.is_gpio_chip =
      !ec && subsystem.filename() == "gpio" && subsystem.parent_path().filename() == "bus";
  facts.driver = sysfs_driver_of(dir.parent_path());
  return facts;
}

EndpointVerdict judge_gpio_chip(const std::string& chip_dir, const GpioChipFacts& facts) {
  if (!facts.exists) return {Kind::kUnusable, "there is no directory " + chip_dir};
  if (!facts.is_gpio_chip) {
    return {Kind::kUnusable, chip_dir +
                                 " is not a GPIO chip's sysfs directory (a gpio-sim chip's is "
                                 "/sys/devices/platform/gpio-sim.N/gpiochipM)"};
  }
  if (facts.driver == "gpio-sim") return {Kind::kSimulated, chip_dir + " is a gpio-sim chip"};
  return {Kind::kReal,
          chip_dir + " is a GPIO chip of " +
              (facts.driver.empty() ? std::string("no driver") : "driver '" + facts.driver + "'") +
              ", not gpio-sim"};
}

// Every joint's chip (one "CHIP_DIR,PWM_FILE" pair per joint, ';' between them): the first that
// is not a gpio-sim chip decides, else the first's.
EndpointVerdict judge_endpoint(const config::Config&, const std::string& endpoint) {
  EndpointVerdict first;
  for (std::size_t at = 0, i = 0;; ++i) {
    const std::size_t end = endpoint.find(';', at);
    const std::string one = endpoint.substr(at, end == std::string::npos ? end : end - at);
    const std::string chip = one.substr(0, one.find(','));
    EndpointVerdict v = judge_gpio_chip(chip, read_gpio_chip(chip));
    if (v.kind != Kind::kSimulated) return v;
    if (i == 0) first = v;
    if (end == std::string::npos) return first;
    at = end + 1;
  }
}

}  // namespace hapticd::sim::gpio
