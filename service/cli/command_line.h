// hapticd's command line: one registration function per sub-command (its options, its help
// with the exit codes it can end with, what runs it), and the one place where an error class
// becomes its exit code (docs/operations.md). Not RT-safe.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "service/config_source.h"

namespace CLI {
class App;
class Validator;
}  // namespace CLI

namespace hapticd::service::cli {

// A sub-command, registered on the app: `run` is called when it was the one given, after
// parsing, and returns the exit code.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
  // Supervises the stop signals itself (run, peer, identify); the others die of them, since
  // they enable nothing.
  bool supervises_stop_signals = false;
};

// Parses the command line, runs the sub-command given and returns its exit code; a parse
// error is exit 2 (or 0 for --help and --version).
int command_line(int argc, char** argv);

// The sub-commands, in the order `hapticd --help` lists them (cli/commands.cpp and
// cli/more_commands.cpp).
std::vector<Command> register_commands(CLI::App& app);
std::vector<Command> register_more_commands(CLI::App& app);

// What every command that reads a configuration takes: --config FILE and repeated --set.
void add_config_options(CLI::App* command, ConfigOptions& config);
// A duration in seconds that ends: finite, > 0, at most 1e9.
const CLI::Validator& seconds();

}  // namespace hapticd::service::cli
