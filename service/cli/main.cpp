// hapticd's entry point: the signal policy first, then the command line (cli/command_line.h).
#include "service/cli/command_line.h"
#include "service/stop_signals.h"

int main(int argc, char** argv) {
  // Before anything else, and before any thread exists: no signal may end the process while
  // output could be enabled (see stop_signals.h).
  hapticd::service::install_signal_policy();
  return hapticd::service::cli::command_line(argc, argv);
}
