// Why a system call failed, in the words every layer uses: the C library's text for an errno
// value ("No such device"), so a fault, a log line and an exception say it the same way.
#pragma once

#include <string>

namespace hapticd::base {

// Not RT-safe (allocates); safe on any thread, unlike std::strerror. "Unknown error N" for a
// value the C library does not know.
std::string errno_text(int err);

}  // namespace hapticd::base
