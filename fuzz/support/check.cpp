#include "support/check.h"

#include <cstdio>
#include <cstdlib>

namespace hapticd::fuzz {

void require(bool ok, std::string_view what, std::string_view detail) {
  if (ok) return;
  std::fprintf(stderr, "fuzz invariant violated: %.*s (%.*s)\n", static_cast<int>(what.size()),
               what.data(), static_cast<int>(detail.size()), detail.data());
  std::abort();
}

}  // namespace hapticd::fuzz
