#include "service/commands/devices_command.h"

#include <string>

#include "service/exit_codes.h"
#include "service/result_output.h"
#include "wiring/registry.h"

namespace hapticd::service {

int devices_command() {
  std::string out;
  for (const wiring::DriverEntry& d : wiring::registered_drivers()) {
    if (d.list_devices != nullptr) out += d.list_devices();
  }
  if (out.empty()) out = "no driver of this build lists devices (it has only the simulator)\n";
  return write_stdout(out) ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
