#include "base/errno_text.h"

#include <string.h>

namespace hapticd::base {

std::string errno_text(int err) {
  // The GNU strerror_r (glibc, _GNU_SOURCE as g++ and clang++ define it): it returns the
  // text, which for a known errno is a constant string and for an unknown one is written in
  // `buf`. std::strerror may share one buffer between threads.
  char buf[64];
  return ::strerror_r(err, buf, sizeof buf);
}

}  // namespace hapticd::base
