#include "service/run/run_command.h"

#include "service/config_source.h"
#include "service/run/run_session.h"

namespace hapticd::service {

int run_command(const RunOptions& options, SignalWatch& signals) {
  RunSession session(options, load_config(options.config), signals);
  return session.run();
}

}  // namespace hapticd::service
