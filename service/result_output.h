// Results go to standard output; a result that cannot be written is a failure the user must
// hear about (`check > /dev/full` must not exit 0 with the verdict lost).
#pragma once

#include <ostream>
#include <string>
#include <string_view>

namespace hapticd::service {

// Not RT-safe. Writes `text` to stdout and flushes; on failure says so on stderr (which may
// fail too: then the exit code is all that is left) and returns false.
bool write_stdout(std::string_view text);

// Not RT-safe. Flushes `out` and checks it; on failure says "hapticd: WHAT: cannot write:
// REASON" on stderr and returns false. REASON is errno's: set errno = 0 before the writes.
bool finish_output(std::ostream& out, const std::string& what);

}  // namespace hapticd::service
