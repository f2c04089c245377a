// libFuzzer target: the input as the bytes of a tick log file, read as `hapticd export` and
// the replay operator read one. Invariants: support/log_oracle.h.
#include <cstddef>
#include <cstdint>

#include "support/log_oracle.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hapticd::fuzz::check_log_read({data, size});
  return 0;
}
