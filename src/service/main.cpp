// hapticd: the one place where the sub-commands are wired to the command line and where
// every error class is mapped to its exit code (docs/operations.md).
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <iostream>
#include <memory>
#include <optional>

#include "config/config_loader.h"
#include "drivers/device.h"
#include "service/check_command.h"
#include "service/curves_command.h"
#include "service/design_coupling_command.h"
#include "service/devices_command.h"
#include "service/exit_codes.h"
#include "service/export_command.h"
#include "service/identify_command.h"
#include "service/peer_command.h"
#include "service/replay_command.h"
#include "service/result_output.h"
#include "service/run_command.h"
#include "service/stop_signals.h"
#include "service/udev_rules.h"
#include "service/verify_command.h"

namespace {

using hapticd::service::ConfigOptions;

void add_config_options(CLI::App* cmd, ConfigOptions& c) {
  cmd->add_option("--config", c.path,
                  "YAML configuration file (default: the embedded config/sim.yaml)");
  cmd->add_option("--set", c.sets,
                  "Override one key before validation, e.g. --set wall.stiffness=3000 or "
                  "--set wall.coupling.numerator=[0.1,-0.07] (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
}

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

// Whether standard error is a stream to the journal (a service's, as systemd sets
// $JOURNAL_STREAM to its device and inode): journald then reads a "<N>" prefix as the line's
// syslog priority (sd-daemon(3)), so `journalctl -p warning` finds the warnings and errors.
bool stderr_is_journal() {
  const char* stream = std::getenv("JOURNAL_STREAM");
  struct stat st {};
  if (stream == nullptr || fstat(STDERR_FILENO, &st) != 0) return false;
  unsigned long long dev = 0, ino = 0;
  return std::sscanf(stream, "%llu:%llu", &dev, &ino) == 2 && dev == st.st_dev && ino == st.st_ino;
}

// The "<N>" of an event's level; the journal has its own time stamps and unit name.
class JournalPriority : public spdlog::custom_flag_formatter {
 public:
  static const char* priority(spdlog::level::level_enum level) {
    switch (level) {
      case spdlog::level::critical:
        return SD_CRIT;
      case spdlog::level::err:
        return SD_ERR;
      case spdlog::level::warn:
        return SD_WARNING;
      case spdlog::level::info:
        return SD_INFO;
      default:
        return SD_DEBUG;  // trace, debug
    }
  }
  void format(const spdlog::details::log_msg& msg, const std::tm&,
              spdlog::memory_buf_t& dest) override {
    const char* p = priority(msg.level);
    dest.append(p, p + std::strlen(p));
  }
  std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<JournalPriority>();
  }
};

// Events (gate verdict, faults, lifecycle) go to stderr; stdout carries only the results a
// script reads (the check table or JSON, the run summary). Returns the prefix of an error
// line written to stderr directly.
const char* set_up_event_log() {
  spdlog::set_default_logger(spdlog::stderr_color_mt("hapticd"));
  if (!stderr_is_journal()) return "";
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<JournalPriority>('*').set_pattern("%*[%l] %v");
  spdlog::set_formatter(std::move(formatter));
  return SD_ERR;
}

}  // namespace

int main(int argc, char** argv) {
  // Before anything else, and before any thread exists: no signal may end the process while
  // output could be enabled (see stop_signals.h).
  hapticd::service::install_signal_policy();
  CLI::App app{
      "hapticd: real-time haptic servo daemon. Renders a virtual wall on a one-axis haptic "
      "device and refuses to enable the motor unless the sampled-data loop is proven passive."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "hapticd 0.1.0");

  ConfigOptions check_cfg;
  bool check_json = false;
  CLI::App* check = app.add_subcommand(
      "check",
      "Print the startup gate's analysis (passivity bound, largest passing stiffness, oscillation "
      "criteria, coupling check) without touching hardware. Exit 0 pass, 3 fail, 2 bad input.");
  add_config_options(check, check_cfg);
  check->add_flag("--json", check_json, "Print exactly one JSON object instead of the table");

  hapticd::service::RunOptions run_opts;
  std::optional<double> duration;
  CLI::App* run = app.add_subcommand(
      "run",
      "Run the servo loop: gate, enable output, render the wall until --duration ends, SIGINT or "
      "SIGTERM, or a fault; then command zero force, disable output, flush the log and print a "
      "summary. Exit 0 clean stop, 1 fault, 2 bad input, 3 gate refused, 4 device error.");
  add_config_options(run, run_opts.config);
  run->add_option("--duration", duration, "Stop after this many seconds (default: until a signal)")
      ->check(CLI::Validator(check_duration, "SECONDS"));
  run->add_option("--log", run_opts.log_path,
                  "Write the binary tick log here (overrides telemetry.log)");
  run->add_option("--summary-json", run_opts.summary_json_path,
                  "Also write the run summary as one JSON object to this file");
  run->add_option("--socket", run_opts.socket_path,
                  "Serve the control socket here (hapticctl: status, stop, reload, clear-fault)");
  std::string on_fault = "exit";
  run->add_option("--on-fault", on_fault,
                  "exit: a fault ends the run (exit 1); hold: the fault latches with output "
                  "off and the daemon waits for `hapticctl clear-fault` or a stop")
      ->check(CLI::IsMember({"exit", "hold"}));
  run->add_flag("--loopback", run_opts.loopback,
                "Drive the configured driver's own protocol code against its simulated peer "
                "(the plant of device.sim) instead of hardware: try a hardware configuration "
                "with no hardware");

  ConfigOptions verify_cfg;
  bool verify_json = false;
  CLI::App* verify = app.add_subcommand(
      "verify",
      "Confirm the passivity bound by measurement: drive the sim loop (freerun) with an imposed "
      "motion in contact over frequencies up to Nyquist, find the device damping below which it "
      "delivers net energy, and compare with the analytic b_req. Exit 0 agree, 1 disagree, 2 bad "
      "input.");
  add_config_options(verify, verify_cfg);
  verify->add_flag("--json", verify_json, "Print exactly one JSON object instead of the table");

  std::string export_log, export_out;
  CLI::App* exp = app.add_subcommand(
      "export",
      "Write a tick log as CSV (one row per tick: times, position, penetration, velocity, forces, "
      "flags). A log cut short exports every complete block and warns. Exit 0, or 2 for a file "
      "that is not a tick log.");
  exp->add_option("log", export_log, "Tick log written by `hapticd run --log`")->required();
  exp->add_option("--out", export_out, "CSV file to write (default: stdout)");

  hapticd::service::PeerOptions peer_opts;
  std::optional<double> peer_duration;
  CLI::App* peer = app.add_subcommand(
      "peer",
      "Run the configured driver's simulated device (the plant of device.sim) on a kernel "
      "endpoint - a USB HID gadget's /dev/hidgN, /dev/raw-gadget or /dev/uhid, a CAN interface, a "
      "gpio-sim chip - until SIGINT/SIGTERM or --duration, so `hapticd run` (or another master) "
      "can drive it through the kernel as it would hardware. Only on the kernel's simulations "
      "(vcan/vxcan, gpio-sim, dummy_hcd's UDC, uhid) unless --impersonate-on-real-hardware "
      "(else exit 2); on CAN it first asks and listens for the configured node and refuses when "
      "one answers (exit 4).");
  add_config_options(peer, peer_opts.config);
  peer->add_option("--endpoint", peer_opts.endpoint,
                   "Where the device lives; the driver says what it takes (docs/drivers/)")
      ->required();
  peer->add_option("--duration", peer_duration, "Stop after this many seconds")
      ->check(CLI::Validator(check_duration, "SECONDS"));
  peer->add_flag("--impersonate-on-real-hardware", peer_opts.policy.impersonate_on_real_hardware,
                 "Also play the device on real hardware (a CAN controller, a GPIO chip that is "
                 "not gpio-sim, a USB device controller that is not dummy_hcd's), where it "
                 "answers beside or instead of a real device");
  peer->add_option("--listen", peer_opts.policy.listen_s,
                   "CAN: seconds to listen for a node already answering at device.can.node_id "
                   "before the peer takes that id")
      ->default_str("2")
      ->check(CLI::Validator(check_duration, "SECONDS"));

  hapticd::service::ReplayOptions replay_opts;
  CLI::App* replay = app.add_subcommand(
      "replay",
      "Feed a tick log's positions through a controller built from the log's own configuration "
      "(the forces must come back bit for bit: exit 0, else 1) and, with --config OTHER or "
      "--set, through that configuration: its gate verdict and a side-by-side summary (exit 3 "
      "when its gate fails). Reads every segment of a rotated log.");
  replay->add_option("LOG", replay_opts.log_path, "Tick log (its first segment's name)")
      ->required();
  add_config_options(replay, replay_opts.other);
  replay->get_option("--config")
      ->description(
          "Another configuration to replay the log through (what-if); --set alone "
          "changes the log's own");
  replay->add_option("--out", replay_opts.out_path,
                     "Write the force series as CSV: tick, position, force_logged, "
                     "force_replayed (and force_other)");
  replay->add_flag("--json", replay_opts.json, "Print exactly one JSON object");

  ConfigOptions curves_cfg;
  bool curves_no_measure = false;
  CLI::App* curves = app.add_subcommand(
      "curves",
      "The gate's analysis as curves, one JSON object (what tools/hapticd-plot draws): the "
      "Z-width (largest passing stiffness for each wall damping) with the configured point and "
      "points measured on the simulated loop, and the Nyquist plot of the oscillation check's "
      "loop gain L with its criteria. Exit 0, 2 bad input.");
  add_config_options(curves, curves_cfg);
  curves->add_flag("--no-measure", curves_no_measure,
                   "Leave out the measured points (they take a few seconds of simulation)");

  hapticd::service::IdentifyOptions id_opts;
  CLI::App* identify = app.add_subcommand(
      "identify",
      "With the device held free (no wall), drive it with a multisine force within "
      "device.max_force and fit its mass m and viscous damping b (and Coulomb friction where it "
      "fits better) on the exact ZOH model; print them with 95 % intervals and the YAML to "
      "paste. The sim, and --loopback, run the simulated device with no operator. Exit 0, 1 a "
      "fault during the excitation, 2 bad input, 4 device error.");
  add_config_options(identify, id_opts.config);
  identify->add_flag("--json", id_opts.json, "Print exactly one JSON object");
  identify->add_flag("--loopback", id_opts.loopback,
                     "The configured driver against its simulated peer instead of hardware");
  identify->add_flag("--yes-the-device-is-free", id_opts.device_free,
                     "Required on real hardware: nothing holds the device and its travel is clear");
  identify->add_option("--amplitude", id_opts.amplitude,
                       "Peak force (N), at most device.max_force (default 0.4 device.max_force)");
  identify->add_option("--f-low", id_opts.f_low, "Lowest frequency (Hz) of the multisine");
  identify->add_option("--f-high", id_opts.f_high, "Highest frequency (Hz), below Nyquist");
  identify->add_option("--duration", id_opts.duration_s, "Seconds of excitation (default 8)");
  identify->add_option("--max-travel", id_opts.max_travel,
                       "Metres from the start the device may move before the excitation stops "
                       "as a fault (default 0.1)");

  hapticd::service::DesignCouplingOptions design_opts;
  CLI::App* design = app.add_subcommand(
      "design-coupling",
      "Design the virtual coupling C(z) for the configured wall, device damping, rate and delay "
      "(Naghshtabrizi and Hespanha: the most transparent C that passes their Theorem 1, by cone "
      "complementarity on an SDP solver), verify it with the gate and print the wall.coupling "
      "YAML to paste, its transparency and static stiffness. A progress line per step on stderr. "
      "Exit 0 designed (or none needed: the wall passes bare), 1 not converged or refused by the "
      "gate, 2 bad input.");
  add_config_options(design, design_opts.config);
  design->add_option("--order", design_opts.order, "Degree of C(z), 1 to 8 (default 3)");
  design->add_option("--weight", design_opts.weight,
                     "felt: the configured transparency weight from --felt-from-hz up (default); "
                     "configured: analysis.transparency_weight as is (the paper's criterion)");
  design->add_option("--felt-from-hz", design_opts.felt_from_hz,
                     "Lower edge of the felt band (default 1 Hz): below it a push is steady");
  design->add_option("--max-steps", design_opts.max_steps,
                     "Outer steps of the first stage (default 24; the pole search that shapes "
                     "its result has its own budget of 100)");
  design->add_option("--max-iterations", design_opts.max_iterations,
                     "Cone complementarity iterations per step (default 12)");
  design->add_flag("--json", design_opts.json, "Print exactly one JSON object");

  ConfigOptions rules_cfg;
  std::string rules_instance;
  CLI::App* rules = app.add_subcommand(
      "udev-rules",
      "Print the udev rules this configuration's instance needs, and nothing more: its CAN "
      "interface's bitrate (no other interface), its GPIO chip and its one PWM channel, its HID "
      "device's node by vendor and product id, each for group hapticd. Installing hapticd "
      "adds none of these; write them to /etc/udev/rules.d/70-hapticd-NAME.rules. Exit 0, 2 "
      "for a configuration a rule cannot match exactly.");
  add_config_options(rules, rules_cfg);
  rules->add_option("--instance", rules_instance,
                    "The systemd instance NAME (hapticd@NAME), for the comments (default: the "
                    "configuration file's name without .yaml)");

  CLI::App* devices = app.add_subcommand(
      "devices",
      "List the devices the drivers find attached (HID through hidapi's hidraw and libusb "
      "backends), each with the configuration keys that select it.");

  const char* const error_prefix = set_up_event_log();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? hapticd::kExitOk : hapticd::kExitUsage;
  }

  // Only `run` and `peer` supervise the stop signals; the others die of them (they enable
  // nothing).
  if (!*run && !*peer && !*identify) hapticd::service::release_stop_signals();
  try {
    if (*check) return hapticd::service::check_command(check_cfg, check_json);
    if (*run) {
      run_opts.duration_s = duration;
      run_opts.on_fault_hold = on_fault == "hold";
      hapticd::service::SignalWatch signals;
      return hapticd::service::run_command(run_opts, signals);
    }
    if (*verify) return hapticd::service::verify_command(verify_cfg, verify_json);
    if (*peer) {
      peer_opts.duration_s = peer_duration;
      hapticd::service::SignalWatch signals;
      return hapticd::service::peer_command(peer_opts, signals);
    }
    if (*exp) return hapticd::service::export_command(export_log, export_out);
    if (*replay) return hapticd::service::replay_command(replay_opts);
    if (*devices) return hapticd::service::devices_command();
    if (*rules) return hapticd::service::udev_rules_command(rules_cfg, rules_instance);
    if (*curves) return hapticd::service::curves_command(curves_cfg, !curves_no_measure);
    if (*design) return hapticd::service::design_coupling_command(design_opts);
    if (*identify) {
      hapticd::service::SignalWatch signals;
      return hapticd::service::identify_command(id_opts, signals);
    }
  } catch (const hapticd::config::ConfigError& e) {
    for (const std::string& m : e.messages()) std::cerr << error_prefix << "hapticd: " << m << "\n";
    return hapticd::kExitUsage;
  } catch (const hapticd::DeviceError& e) {
    std::cerr << error_prefix << "hapticd: device error: " << e.what() << "\n";
    return hapticd::kExitDevice;
  } catch (const std::exception& e) {
    std::cerr << error_prefix << "hapticd: " << e.what() << "\n";
    return hapticd::kExitRuntimeFault;
  }
  return hapticd::kExitUsage;
}
