#include "drivers/gpio/gpio_driver.h"

#include <stdexcept>

#include "config/config_loader.h"
#include "drivers/gpio/gpio_device.h"
#include "drivers/gpio/kernel_transport.h"
#include "drivers/gpio/loopback_transport.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/gpio/gpio_peer.h"

namespace hapticd::drivers::gpio {
namespace {

int delay(const config::Config& cfg) {
  return declared_delay_samples(gpio_settings(cfg), cfg.loop.sample_period_s());
}

std::unique_ptr<Device> make_device(const config::Config& cfg) {
  const GpioSettings& s = gpio_settings(cfg);
  return std::make_unique<GpioDevice>(s, cfg.device.max_force, std::make_unique<KernelTransport>(s),
                                      delay(cfg));
}

Loopback make_loopback(const config::Config& cfg) {
  const GpioSettings& s = gpio_settings(cfg);
  auto [driver_end, peer_end] = io::seqpacket_pair();
  std::unique_ptr<sim::LoopbackPeer> peer;
  try {
    peer = sim::gpio::make_loopback_peer(cfg, std::move(peer_end));
  } catch (const std::invalid_argument& e) {  // SimAxis: a plant that cannot be simulated
    throw config::ConfigError({cfg.locate("device.sim") + ": device.sim: " + e.what()});
  }
  auto device = std::make_unique<GpioDevice>(
      s, cfg.device.max_force, std::make_unique<LoopbackTransport>(std::move(driver_end)),
      delay(cfg));
  return {std::move(device), std::move(peer)};
}

}  // namespace

DriverEntry gpio_driver() {
  DriverEntry e;
  e.name = "gpio";
  e.summary = "quadrature encoder on GPIO lines (libgpiod) and a sysfs PWM motor driver";
  e.read_section = &read_gpio_section;
  e.declared_delay = &delay;
  e.make_device = &make_device;
  e.make_loopback = &make_loopback;
  e.make_peer_on = [](const config::Config& cfg, const std::string& endpoint) {
    return std::unique_ptr<sim::LoopbackPeer>(sim::gpio::make_kernel_peer(cfg, endpoint));
  };
  return e;
}

}  // namespace hapticd::drivers::gpio
