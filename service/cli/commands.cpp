// Every sub-command of hapticd on the command line: one registration function each, with its
// options, its help (the exit codes it can end with) and what runs it.
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "config/config_loader.h"
#include "drivers/device.h"
#include "service/cli/command_line.h"
#include "service/cli/event_log.h"
#include "service/commands/check_command.h"
#include "service/commands/curves_command.h"
#include "service/commands/design_coupling_command.h"
#include "service/commands/devices_command.h"
#include "service/commands/export_command.h"
#include "service/commands/identify_command.h"
#include "service/commands/peer_command.h"
#include "service/commands/replay_command.h"
#include "service/commands/udev_rules.h"
#include "service/commands/verify_command.h"
#include "service/exit_codes.h"
#include "service/run/run_command.h"
#include "service/stop_signals.h"

namespace hapticd::service::cli {
namespace {

// A run that ends by itself: finite, positive, and short enough that its tick count fits.
std::string check_duration(const std::string& text) {
  double v = 0.0;
  try {
    std::size_t used = 0;
    v = std::stod(text, &used);
    if (used != text.size()) return "must be a number of seconds, got '" + text + "'";
  } catch (const std::exception&) {
    return "must be a number of seconds, got '" + text + "'";
  }
  if (!std::isfinite(v) || v <= 0.0)
    return "must be a finite number of seconds > 0, got '" + text + "'";
  if (v > 1e9) return "must be at most 1e9 s (about 31 years), got '" + text + "'";
  return "";
}

// A command's options live as long as the app: each registration owns its own.
template <typename T>
std::shared_ptr<T> options() {
  return std::make_shared<T>();
}

Command check(CLI::App& app) {
  auto o = options<std::pair<ConfigOptions, bool>>();
  CLI::App* c = app.add_subcommand(
      "check",
      "Print the startup gate's analysis (passivity bound, largest passing stiffness, oscillation "
      "criteria, coupling check) without touching hardware. Exit 0 pass, 3 fail, 2 bad input.");
  add_config_options(c, o->first);
  c->add_flag("--json", o->second, "Print exactly one JSON object instead of the table");
  return {c, [o] { return check_command(o->first, o->second); }};
}

struct RunArgs {
  RunOptions run;
  std::optional<double> duration;
  std::string on_fault = "exit";
};

Command run(CLI::App& app) {
  auto o = options<RunArgs>();
  CLI::App* c = app.add_subcommand(
      "run",
      "Run the servo loop: gate, enable output, render the wall until --duration ends, SIGINT or "
      "SIGTERM, or a fault; then command zero force, disable output, flush the log and print a "
      "summary. Exit 0 clean stop, 1 fault, 2 bad input, 3 gate refused, 4 device error.");
  add_config_options(c, o->run.config);
  c->add_option("--duration", o->duration, "Stop after this many seconds (default: until a signal)")
      ->check(seconds());
  c->add_option("--log", o->run.log_path,
                "Write the binary tick log here (overrides telemetry.log)");
  c->add_option("--summary-json", o->run.summary_json_path,
                "Also write the run summary as one JSON object to this file");
  c->add_option("--socket", o->run.socket_path,
                "Serve the control socket here (hapticctl: status, stop, reload, clear-fault)");
  c->add_option("--on-fault", o->on_fault,
                "exit: a fault ends the run (exit 1); hold: the fault latches with output "
                "off and the daemon waits for `hapticctl clear-fault` or a stop")
      ->check(CLI::IsMember({"exit", "hold"}));
  c->add_flag("--loopback", o->run.loopback,
              "Drive the configured driver's own protocol code against its simulated peer "
              "(the plant of device.sim) instead of hardware: try a hardware configuration "
              "with no hardware");
  return {c,
          [o] {
            o->run.duration_s = o->duration;
            o->run.on_fault_hold = o->on_fault == "hold";
            SignalWatch signals;
            return run_command(o->run, signals);
          },
          true};
}

Command verify(CLI::App& app) {
  auto o = options<std::pair<ConfigOptions, bool>>();
  CLI::App* c = app.add_subcommand(
      "verify",
      "Confirm the passivity bound by measurement: drive the sim loop (freerun) with an imposed "
      "motion in contact over frequencies up to Nyquist, find the device damping below which it "
      "delivers net energy, and compare with the analytic b_req. Exit 0 agree, 1 disagree, 2 bad "
      "input.");
  add_config_options(c, o->first);
  c->add_flag("--json", o->second, "Print exactly one JSON object instead of the table");
  return {c, [o] { return verify_command(o->first, o->second); }};
}

Command export_log(CLI::App& app) {
  auto o = options<std::pair<std::string, std::string>>();
  CLI::App* c = app.add_subcommand(
      "export",
      "Write a tick log as CSV (one row per tick: times, position, penetration, velocity, forces, "
      "flags). A log cut short exports every complete block and warns. Exit 0, or 2 for a file "
      "that is not a tick log.");
  c->add_option("log", o->first, "Tick log written by `hapticd run --log`")->required();
  c->add_option("--out", o->second, "CSV file to write (default: stdout)");
  return {c, [o] { return export_command(o->first, o->second); }};
}

Command replay(CLI::App& app) {
  auto o = options<ReplayOptions>();
  CLI::App* c = app.add_subcommand(
      "replay",
      "Feed a tick log's positions through a controller built from the log's own configuration "
      "(the forces must come back bit for bit: exit 0, else 1) and, with --config OTHER or "
      "--set, through that configuration: its gate verdict and a side-by-side summary (exit 3 "
      "when its gate fails). Reads every segment of a rotated log.");
  c->add_option("LOG", o->log_path, "Tick log (its first segment's name)")->required();
  add_config_options(c, o->other);
  c->get_option("--config")
      ->description(
          "Another configuration to replay the log through (what-if); --set alone changes the "
          "log's own");
  c->add_option("--out", o->out_path,
                "Write the force series as CSV: tick, position, force_logged, force_replayed "
                "(and force_other)");
  c->add_flag("--json", o->json, "Print exactly one JSON object");
  return {c, [o] { return replay_command(*o); }};
}

Command devices(CLI::App& app) {
  CLI::App* c = app.add_subcommand(
      "devices",
      "List the devices the drivers find attached (HID through hidapi's hidraw and libusb "
      "backends, force-feedback input devices, USB serial ports, Novint Falcons), each with the "
      "configuration keys that select it.");
  return {c, [] { return devices_command(); }};
}

// The command given, run; what escapes it mapped to its exit code.
int run_guarded(const Command& command, const char* error_prefix) {
  // Only the commands that enable output supervise the stop signals; the others die of them.
  if (!command.supervises_stop_signals) release_stop_signals();
  try {
    return command.run();
  } catch (const config::ConfigError& e) {
    for (const std::string& m : e.messages()) std::cerr << error_prefix << "hapticd: " << m << "\n";
    return kExitUsage;
  } catch (const DeviceError& e) {
    std::cerr << error_prefix << "hapticd: device error: " << e.what() << "\n";
    return kExitDevice;
  } catch (const std::exception& e) {
    std::cerr << error_prefix << "hapticd: " << e.what() << "\n";
    return kExitRuntimeFault;
  }
}

}  // namespace

void add_config_options(CLI::App* command, ConfigOptions& config) {
  command->add_option("--config", config.path,
                      "YAML configuration file (default: the embedded config/sim.yaml)");
  command
      ->add_option("--set", config.sets,
                   "Override one key before validation, e.g. --set wall.stiffness=3000 or "
                   "--set wall.coupling.numerator=[0.1,-0.07] (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
}

const CLI::Validator& seconds() {
  static const CLI::Validator v(check_duration, "SECONDS");
  return v;
}

std::vector<Command> register_commands(CLI::App& app) {
  std::vector<Command> all;
  for (Command (*add)(CLI::App&) : {check, run, verify, export_log, replay}) {
    all.push_back(add(app));
  }
  for (Command& c : register_more_commands(app)) all.push_back(std::move(c));
  all.push_back(devices(app));
  return all;
}

int command_line(int argc, char** argv) {
  CLI::App app{
      "hapticd: real-time haptic servo daemon. Renders a virtual wall on a one-axis haptic "
      "device and refuses to enable the motor unless the sampled-data loop is proven passive."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "hapticd 0.1.0");
  const std::vector<Command> commands = register_commands(app);
  const char* const error_prefix = set_up_event_log();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitUsage;
  }
  for (const Command& c : commands) {
    if (*c.app) return run_guarded(c, error_prefix);
  }
  return kExitUsage;
}

}  // namespace hapticd::service::cli
