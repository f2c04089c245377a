// hapticctl: the control socket's command-line client (docs/operations.md). One request per
// run; human output by default, the daemon's answer as one JSON object with --json. Exit codes
// follow docs/operations.md: 0 done, 1 refused or failed (or no daemon to ask), 2 usage or an
// invalid configuration, 3 a reload the gate refused.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "base/errno_text.h"
#include "client/connection.h"
#include "service/control/ctl_output.h"
#include "service/exit_codes.h"

namespace {

using nlohmann::json;

// The file a reload sends, read here: the daemon may not be allowed to read it.
bool read_text(const std::string& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  text = s.str();
  return !in.bad();
}

// Prints the answer; the exit code it means.
int report(const json& answer, const std::string& command, bool as_json) {
  const bool ok = answer.value("ok", false);
  if (as_json) {
    std::cout << answer.dump(-1, ' ', false, json::error_handler_t::replace) << "\n";
  } else if (!ok) {
    std::cerr << "hapticctl: " << command << ": "
              << answer.value("error", std::string("refused without a reason")) << "\n";
  } else if (command == "status") {
    std::cout << hapticd::service::status_text(answer["status"]);
  } else if (command == "reload") {
    std::cout << hapticd::service::reload_text(answer["reload"]);
  } else if (command == "scene") {
    std::cout << hapticd::service::reload_text(answer["scene"]);
  } else if (command == "stop") {
    std::cout << "stopping: zero force, output disabled, log flushed\n";
  } else {
    std::cout << "fault cleared: output enabled again through the gate\n";
  }
  if (ok) return hapticd::kExitOk;
  const int code = answer.value("code", 1);
  return code >= 1 && code <= 4 ? code : hapticd::kExitRuntimeFault;
}

// hapticctl stream: the daemon's state stream, each sample a line of JSON on stdout.
int print_stream(const std::string& socket, std::uint32_t every, std::uint64_t count,
                 double timeout_s) {
  try {
    const int timeout_ms = static_cast<int>(timeout_s * 1000.0);
    hapticd::client::Connection c(socket, timeout_ms);
    c.stream(every);
    for (std::uint64_t n = 0; count == 0 || n < count; ++n) {
      const std::optional<json> sample = c.next_sample(timeout_ms);
      if (!sample) {
        std::cerr << "hapticctl: stream: no sample within " << timeout_s << " s\n";
        return hapticd::kExitRuntimeFault;
      }
      std::cout << sample->dump() << "\n" << std::flush;
    }
    return hapticd::kExitOk;
  } catch (const hapticd::client::Refused& e) {
    std::cerr << "hapticctl: stream refused: " << e.what() << "\n";
    return e.code();
  } catch (const hapticd::client::ClientError& e) {
    std::cerr << "hapticctl: " << e.what() << "\n";
    return hapticd::kExitRuntimeFault;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "hapticctl: ask a running hapticd through its control socket (status, stop, reload, "
      "clear-fault, scene). Exit 0 done, 1 refused or failed, 2 usage or invalid configuration, 3 "
      "a "
      "reload the gate refused."};
  app.require_subcommand(1);
  std::string socket, instance = "hapticd";
  bool as_json = false;
  double timeout_s = 30.0;
  app.add_option("--socket", socket, "The daemon's control socket (hapticd run --socket)");
  app.add_option("-i,--instance", instance,
                 "Instance of hapticd@.service: the socket /run/hapticd/INSTANCE/control.sock "
                 "(default: hapticd)")
      ->excludes("--socket");
  app.add_flag("--json", as_json, "Print the daemon's answer as one JSON object");
  app.add_option("--timeout", timeout_s, "Seconds to wait for the answer")
      ->check(CLI::Range(0.1, 3600.0));
  app.add_subcommand("status", "State, tick, timing, gate verdict, wall energy, fault");
  app.add_subcommand("stop", "Stop the servo: zero force, output disabled, log flushed");
  std::string file;
  CLI::App* reload =
      app.add_subcommand("reload",
                         "Send FILE's configuration: parsed, checked and gated by the daemon, then "
                         "swapped in at a tick boundary, or refused with the reason");
  reload->add_option("FILE", file, "YAML configuration")->required();
  app.add_subcommand("clear-fault",
                     "Re-arm after a latched fault (hapticd run --on-fault hold): only through "
                     "the gate and with the device outside the wall");
  CLI::App* scene = app.add_subcommand(
      "scene",
      "Change the walls of a device of several joints: checked and gated by the daemon as a "
      "reload, swapped in at a tick boundary, or refused with the reason");
  scene->require_subcommand(1);
  std::string wall_text;
  std::size_t index = 0;
  scene->add_subcommand("add", "Add a wall: WALL is a JSON object of a wall's keys")
      ->add_option("WALL", wall_text,
                   "e.g. '{\"point\": [0.03, 0, 0.11], \"normal\": [1, 0, 0], "
                   "\"stiffness\": 500}'")
      ->required();
  CLI::App* change = scene->add_subcommand("change", "Change keys of walls[INDEX]");
  change->add_option("INDEX", index, "The wall's place in walls (0, 1, ...)")->required();
  change->add_option("WALL", wall_text, "A JSON object of the keys that change")->required();
  scene->add_subcommand("remove", "Remove walls[INDEX]")
      ->add_option("INDEX", index, "The wall's place in walls (0, 1, ...)")
      ->required();
  std::vector<double> point;
  CLI::App* move = scene->add_subcommand(
      "move",
      "Move walls[INDEX] to POINT, with no new gate: refused unless the gate proved the walls "
      "passive wherever they move (hapticd check: 'moved by clients')");
  move->add_option("INDEX", index, "The wall's place in walls (0, 1, ...)")->required();
  move->add_option("POINT", point, "The wall's new point, one number per task axis (m)")
      ->required()
      ->expected(1, 3);
  std::uint32_t every = 10;
  std::uint64_t count = 0;
  CLI::App* stream = app.add_subcommand(
      "stream",
      "Print every EVERY-th tick's state as it comes, one JSON object a line (tick, time_ns, "
      "measured_js, measured_cp, measured_cv, setpoint_cf, ..., missed)");
  stream->add_option("--every", every, "A sample every this many ticks (default 10)")
      ->check(CLI::Range(1, 100000));
  stream->add_option("--count", count, "Stop after this many samples (default: until killed)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? hapticd::kExitOk : hapticd::kExitUsage;
  }
  const std::string command = app.get_subcommands().front()->get_name();
  json req = {{"cmd", command}};
  if (command == "reload") {
    std::string text;
    if (!read_text(file, text)) {
      std::cerr << "hapticctl: " << file << ": cannot read: " << hapticd::base::errno_text(errno)
                << "\n";
      return hapticd::kExitUsage;
    }
    req["config"] = text;
    // Absolute: the daemon resolves the file's relative paths (a replay log) against it.
    req["source"] = std::filesystem::absolute(file).lexically_normal().string();
  }
  if (command == "scene") {
    const std::string op = scene->get_subcommands().front()->get_name();
    req["op"] = op;
    if (op != "add") req["index"] = index;
    if (op == "move") req["point"] = point;
    // An operator's wall stays when hapticctl exits, as a reload's would.
    if (op == "add") req["keep"] = true;
    if (op != "remove" && op != "move") {
      req["wall"] = json::parse(wall_text, nullptr, false);
      if (!req["wall"].is_object()) {
        std::cerr << "hapticctl: scene " << op << ": WALL must be a JSON object, e.g. "
                  << "'{\"stiffness\": 400}'\n";
        return hapticd::kExitUsage;
      }
    }
  }
  if (socket.empty()) socket = hapticd::client::instance_socket(instance);
  if (command == "stream") return print_stream(socket, every, count, timeout_s);
  try {
    const json answer = hapticd::client::request(socket, req, static_cast<int>(timeout_s * 1000.0));
    return report(answer, command, as_json);
  } catch (const hapticd::client::ClientError& e) {
    std::cerr << "hapticctl: " << e.what() << "\n";
    return hapticd::kExitRuntimeFault;
  }
}
