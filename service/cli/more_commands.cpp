// The sub-commands that play or study a device beyond the servo itself: peer, curves,
// identify, design-coupling and udev-rules (cli/command_line.h).
#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "service/cli/command_line.h"
#include "service/commands/curves_command.h"
#include "service/commands/design_coupling_command.h"
#include "service/commands/identify_command.h"
#include "service/commands/peer_command.h"
#include "service/commands/udev_rules.h"
#include "service/stop_signals.h"

namespace hapticd::service::cli {
namespace {

struct PeerArgs {
  PeerOptions peer;
  std::optional<double> duration;
};

Command peer(CLI::App& app) {
  auto o = std::make_shared<PeerArgs>();
  CLI::App* c = app.add_subcommand(
      "peer",
      "Run the configured driver's simulated device (the plant of device.sim) on a kernel "
      "endpoint - a USB HID gadget's /dev/hidgN, /dev/raw-gadget or /dev/uhid, a CAN interface, a "
      "gpio-sim chip - until SIGINT/SIGTERM or --duration, so `hapticd run` (or another master) "
      "can drive it through the kernel as it would hardware. Only on the kernel's simulations "
      "(vcan/vxcan, gpio-sim, dummy_hcd's UDC, uhid) unless --impersonate-on-real-hardware "
      "(else exit 2); on CAN it first asks and listens for the configured node and refuses when "
      "one answers (exit 4).");
  add_config_options(c, o->peer.config);
  c->add_option("--endpoint", o->peer.endpoint,
                "Where the device lives; the driver says what it takes (docs/drivers/)")
      ->required();
  c->add_option("--duration", o->duration, "Stop after this many seconds")->check(seconds());
  c->add_flag("--impersonate-on-real-hardware", o->peer.policy.impersonate_on_real_hardware,
              "Also play the device on real hardware (a CAN controller, a GPIO chip that is "
              "not gpio-sim, a USB device controller that is not dummy_hcd's), where it "
              "answers beside or instead of a real device");
  c->add_option("--listen", o->peer.policy.listen_s,
                "CAN: seconds to listen for a node already answering at device.can.node_id "
                "before the peer takes that id")
      ->default_str("2")
      ->check(seconds());
  return {c,
          [o] {
            o->peer.duration_s = o->duration;
            SignalWatch signals;
            return peer_command(o->peer, signals);
          },
          true};
}

Command curves(CLI::App& app) {
  auto o = std::make_shared<std::pair<ConfigOptions, bool>>();
  CLI::App* c = app.add_subcommand(
      "curves",
      "The gate's analysis as curves, one JSON object (what tools/hapticd-plot draws): the "
      "Z-width (largest passing stiffness for each wall damping) with the configured point and "
      "points measured on the simulated loop, and the Nyquist plot of the oscillation check's "
      "loop gain L with its criteria. Exit 0, 2 bad input.");
  add_config_options(c, o->first);
  c->add_flag("--no-measure", o->second,
              "Leave out the measured points (they take a few seconds of simulation)");
  return {c, [o] { return curves_command(o->first, !o->second); }};
}

Command identify(CLI::App& app) {
  auto o = std::make_shared<IdentifyOptions>();
  CLI::App* c = app.add_subcommand(
      "identify",
      "With the device held free (no wall), drive it with a multisine force within "
      "device.max_force and fit its mass m and viscous damping b (and Coulomb friction where it "
      "fits better) on the exact ZOH model; print them with 95 % intervals and the YAML to "
      "paste. The sim, and --loopback, run the simulated device with no operator. Exit 0, 1 a "
      "fault during the excitation, 2 bad input, 4 device error.");
  add_config_options(c, o->config);
  c->add_flag("--json", o->json, "Print exactly one JSON object");
  c->add_flag("--loopback", o->loopback,
              "The configured driver against its simulated peer instead of hardware");
  c->add_flag("--yes-the-device-is-free", o->device_free,
              "Required on real hardware: nothing holds the device and its travel is clear");
  c->add_option("--amplitude", o->amplitude,
                "Peak force (N), at most device.max_force (default 0.4 device.max_force)");
  c->add_option("--f-low", o->f_low, "Lowest frequency (Hz) of the multisine");
  c->add_option("--f-high", o->f_high, "Highest frequency (Hz), below Nyquist");
  c->add_option("--duration", o->duration_s, "Seconds of excitation (default 8)");
  c->add_option("--joint", o->joint,
                "Of a device of several joints, the one to excite (0-based, as device.mass[J]); "
                "the others are commanded zero");
  c->add_option("--max-travel", o->max_travel,
                "Metres from the start the device may move before the excitation stops as a "
                "fault (default 0.1)");
  return {c,
          [o] {
            SignalWatch signals;
            return identify_command(*o, signals);
          },
          true};
}

Command design_coupling(CLI::App& app) {
  auto o = std::make_shared<DesignCouplingOptions>();
  CLI::App* c = app.add_subcommand(
      "design-coupling",
      "Design the virtual coupling C(z) for the configured wall, device damping, rate and delay "
      "(Naghshtabrizi and Hespanha: the most transparent C that passes their Theorem 1, by cone "
      "complementarity on an SDP solver, then shaped for fixed poles and a pole search), verify "
      "it with the gate and print the wall.coupling YAML to paste, its transparency and static "
      "stiffness. A progress line per step on stderr. Exit 0 designed (or none needed: the wall "
      "passes bare), 1 not converged or refused by the gate, 2 bad input.");
  add_config_options(c, o->config);
  c->add_option("--order", o->order, "Degree of C(z), 1 to 8 (default 3)");
  c->add_option("--weight", o->weight,
                "felt: the configured transparency weight from --felt-from-hz up (default); "
                "configured: analysis.transparency_weight as is (the paper's criterion)");
  c->add_option("--felt-from-hz", o->felt_from_hz,
                "Lower edge of the felt band (default 1 Hz): below it a push is steady");
  c->add_option("--max-steps", o->max_steps,
                "Outer steps of the first stage (default 24; the pole search that shapes its "
                "result has its own budget of 100)");
  c->add_option("--max-iterations", o->max_iterations,
                "Cone complementarity iterations per step (default 12)");
  c->add_flag("--json", o->json, "Print exactly one JSON object");
  return {c, [o] { return design_coupling_command(*o); }};
}

Command udev_rules(CLI::App& app) {
  auto o = std::make_shared<std::pair<ConfigOptions, std::string>>();
  CLI::App* c = app.add_subcommand(
      "udev-rules",
      "Print the udev rules this configuration's instance needs, and nothing more: its CAN "
      "interface's bitrate (no other interface), its GPIO chip and its one PWM channel, its HID "
      "device's node by vendor and product id, its serial port (and an FTDI port's latency "
      "timer), its Novint Falcon's USB device, each for group hapticd. Installing hapticd "
      "adds none of these; write them to /etc/udev/rules.d/70-hapticd-NAME.rules. Exit 0, 2 "
      "for a configuration a rule cannot match exactly.");
  add_config_options(c, o->first);
  c->add_option("--instance", o->second,
                "The systemd instance NAME (hapticd@NAME), for the comments (default: the "
                "configuration file's name without .yaml)");
  return {c, [o] { return udev_rules_command(o->first, o->second); }};
}

}  // namespace

std::vector<Command> register_more_commands(CLI::App& app) {
  std::vector<Command> more;
  for (Command (*add)(CLI::App&) : {peer, curves, identify, design_coupling, udev_rules}) {
    more.push_back(add(app));
  }
  return more;
}

}  // namespace hapticd::service::cli
