// Process exit codes (docs/operations.md).
#pragma once

namespace hapticd {

enum ExitCode : int {
  kExitOk = 0,
  kExitRuntimeFault = 1,
  kExitUsage = 2,  // usage or configuration error
  kExitGateRefused = 3,
  kExitDevice = 4,
};

}  // namespace hapticd
